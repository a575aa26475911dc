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

/// A test's reproducible random numbers in [0, 1): a 64-bit linear congruential generator
/// seeded with `seed` (Knuth's MMIX constants), its top 53 bits.
#[cfg(test)]
fn test_random(mut seed: u64) -> impl FnMut() -> f64 {
    move || {
        seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (seed >> 11) as f64 / (1u64 << 53) as f64
    }
}

pub use avoid::{choose_velocity, Agent};
pub use clearance::{
    clear_foot, foot_may_move, limit_step, nearest_gap, nearest_gaps, Body, Capsule, FootSpan,
    HandReach, Surroundings,
};
pub use crowd::{Crowd, FootprintsAround};
pub use footprint::Footprint;
pub use radius::body_radius;
pub use space::{path_length, Floor, NoPath, Pressed, Space, Walking, Wall, CLEARANCE};
pub use way::{precedence, Precedence};
