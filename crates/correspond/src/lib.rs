//! symcorr-correspond: filled by its issue.
