//! Verification case dem04 (being written).
