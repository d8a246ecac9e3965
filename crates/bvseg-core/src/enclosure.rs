//! (stage to be written)
