//! The registry: every action kind this crate adds to Lua, in one list.
//!
//! A kind is a folder (`reach/`: the generator, its options with `validate()`, and a
//! `lua.rs` that reads those options); adding one means adding its folder, a line here
//! and its section in `docs/lua-api.md`.

use crate::{capture, dynamics, grasp, interact, keyframe, look_at, manipulate, reach, walk};
use troupe_lua::kinds::{ActionKind, ActionKinds, BuildFn, MakeFunction};

/// Each actor method and the builder that reads its Lua arguments.
const KINDS: &[(&str, BuildFn)] = &[
    ("play", keyframe::lua::build_play),
    ("simulate", dynamics::lua::build_simulate),
    ("servo", dynamics::lua::build_servo),
    ("track", dynamics::lua::build_track),
    ("reach", reach::lua::build_reach),
    ("ik", reach::lua::build_ik),
    ("look_at", look_at::lua::build_look_at),
    ("walk", walk::lua::build_walk),
    ("grasp", grasp::lua::build_grasp),
    ("release", grasp::lua::build_release),
    ("place", grasp::lua::build_place),
    ("manipulate", manipulate::lua::build_manipulate),
    ("give", interact::lua::build_give),
    ("receive", interact::lua::build_receive),
    ("hold_hand", interact::lua::build_hold_hand),
    ("shake_hands", interact::lua::build_shake_hands),
    ("capture", capture::lua::build_capture),
];

/// The `troupe` functions that go with the kinds.
const FUNCTIONS: [(&str, MakeFunction); 1] = [("plan_grasp", grasp::lua::make_plan_grasp)];

/// Every action kind implemented here, and the `troupe` functions that go with them,
/// ready for a [`troupe_lua::Director`].
pub fn action_kinds() -> ActionKinds {
    let mut registry = ActionKinds::default();
    for &(method, build) in KINDS {
        registry.register(ActionKind { method, build });
    }
    for (name, make) in FUNCTIONS {
        registry.register_function(name, make);
    }
    registry
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_kind_is_registered_once() {
        let registry = action_kinds();
        assert_eq!(registry.all().len(), KINDS.len());
        for &(method, _) in KINDS {
            assert!(registry.get(method).is_some(), "{method}");
        }
        assert_eq!(registry.functions().len(), 1);
    }
}
