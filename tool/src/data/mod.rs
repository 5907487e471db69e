//! Training pairs.
