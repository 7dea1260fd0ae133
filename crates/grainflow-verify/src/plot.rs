//! Figures (PNG and SVG) for the verification reports.
