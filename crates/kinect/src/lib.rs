//! symcorr-kinect: filled by its issue.
