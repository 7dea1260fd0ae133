//! Verification case rolling (being written).
