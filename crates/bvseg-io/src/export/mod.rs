//! Engine-ready outputs.
