// Placeholder: filled in by the SLAM front-end work (issue 5).
