//! OSC over UDP (rosc): receive poses and glove values from installation tools, send actor
//! poses and action events out.
//!
//! Addresses (all arguments are floats unless said otherwise; ints are accepted for floats):
//!
//! | direction | address | arguments |
//! |---|---|---|
//! | in  | `/troupe/<performer>/<joint>` | `x y z qw qx qy qz`: the joint's world position (m) and orientation, scene frame |
//! | in  | `/troupe/<performer>/glove`   | one value per glove sensor, raw 1…255 |
//! | out | `/troupe/<actor>/<joint>`     | `x y z qw qx qy qz` for every joint, one bundle per actor per tick |
//! | out | `/troupe/event`               | `actor` (string), `action id` (int), `kind` (string), `status` (string), `time` (float) |

pub(crate) mod datagram;
pub(crate) mod error;
pub(crate) mod listener;
pub(crate) mod message;
pub(crate) mod output;

pub use datagram::{decode_datagram, DatagramError, MAX_BUNDLE_DEPTH};
pub use error::OscError;
pub use listener::OscListener;
pub use message::{parse_message, parse_packet, MessageError, OscInput};
pub use output::{OscOut, OscSender};
