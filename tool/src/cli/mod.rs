//! The `diffbsdf` command line.
