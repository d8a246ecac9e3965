//! Mesh loading and result writing for bvseg.
