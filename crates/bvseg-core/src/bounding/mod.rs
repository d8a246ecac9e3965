//! Stage 6: bounding volumes of a part's points.
//!
//! - [`mvee`]: the minimum-volume enclosing ellipsoid (output).
//! - [`obb`]: a tight oriented bounding box (output).
//! - [`hull`]: the convex hull, which both of the above work on.
pub mod hull;
pub mod mvee;
pub mod obb;
