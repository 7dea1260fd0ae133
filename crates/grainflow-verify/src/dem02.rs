//! Verification case dem02 (being written).
