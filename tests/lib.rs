//! Integration tests of strata (see `tests/`); this library is empty.
