//! symcorr-spectral: filled by its issue.
