//! Verification case dem03 (being written).
