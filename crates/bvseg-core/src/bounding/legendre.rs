//! The Legendre ellipsoid of a part, scaled to hold it (to be written).
