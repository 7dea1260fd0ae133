//! Verification case chung_ooi (being written).
