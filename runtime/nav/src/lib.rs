//! troupe's shared space: which parts of the floor a body can stand on and how it gets
//! from one point to another around furniture, walls and other people.
//!
//! Obstacles are [`Footprint`]s, convex polygons in the floor plane (x, z): an object
//! seen from above, a wall, a standing actor's disc. A [`Space`] holds the walls and the
//! walkable [`Floor`] and answers [`Space::path`] on a navigation mesh whose obstacles are
//! inflated by the body's [`body_radius`]. See `docs/navigation.md`.

#![warn(missing_docs)]

pub mod avoid;
pub mod clearance;
pub mod crowd;
pub mod footprint;
pub mod radius;
pub mod space;
pub mod way;

pub use avoid::{choose_velocity, Agent};
pub use clearance::{
    clear_foot, foot_may_move, gap_bound, limit_step, nearest_gap, nearest_gaps, Body, Capsule,
    FootSpan, HandReach, Surroundings,
};
pub use crowd::{Crowd, FootprintsAround};
pub use footprint::Footprint;
pub use radius::body_radius;
pub use space::{path_length, Floor, NoPath, Pressed, Space, Walking, Wall, CLEARANCE};
pub use way::{precedence, Precedence};
