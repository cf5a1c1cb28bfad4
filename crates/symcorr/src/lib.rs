//! symcorr: skeleton-aware human shape correspondence. The pipeline API arrives with the pipeline issue.
