//! Directional functions on the sphere as Haar wavelets (docs/design.md §5.3, docs/method.md §4–§5): the
//! equal-area octahedral map from directions to the unit square, and the orthonormal
//! non-standard 2D Haar transform over it.

pub mod point_map;
pub mod sparse;
pub mod sphere_map;
pub mod transform;

pub use point_map::PointMap;
pub use sparse::{SparseHaar, SparseSum};
pub use sphere_map::{
    direction_to_square, square_to_direction, texel_at, texel_centre, texel_directions, texel_of,
};
pub use transform::{detail_index, Coefficient, Haar2d};
