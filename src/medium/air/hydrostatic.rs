//! Hydrostatic pressure over a temperature profile (next commit).
