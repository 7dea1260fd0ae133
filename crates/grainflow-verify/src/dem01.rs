//! Verification case dem01 (being written).
