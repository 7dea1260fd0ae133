//! MFIX keyword input decks (mfix.dat / .mfx) (being written).
