//! strata application layer (in progress).
