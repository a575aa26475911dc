//! The API reference as data: every global, `troupe` function, handle method and field a
//! script can use, with its parameters, result and one-line doc. `troupe lua-defs` turns
//! it into an EmmyLua / LuaLS `---@meta` file for editors and `emmylua_check`, and tests
//! hold it to the live API both ways (every entry resolves in a real Lua state, every
//! live global, `troupe` function and action kind has an entry), so it cannot drift.

/// What an entry is.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Item {
    /// A function (`wait`, `troupe.actor`), called with `.`.
    Function,
    /// A method of a handle (`actor:behave`), called with `:`.
    Method,
    /// A field of a handle (`action.status`), of this EmmyLua type.
    Field(&'static str),
}

/// One documented name.
#[derive(Clone, Copy, Debug)]
pub struct Entry {
    /// Where it lives: `""` (a global), `troupe`, `troupe.devices`, or a handle class
    /// (`Actor`, `Action`, `Behavior`, `Handler`, `Object`, `Sequence`).
    pub owner: &'static str,
    /// Its name.
    pub name: &'static str,
    /// Function, method or field.
    pub item: Item,
    /// Parameters as `name: type` (EmmyLua types; `name?` is optional).
    pub params: &'static [&'static str],
    /// The result's EmmyLua type (empty: none).
    pub returns: &'static str,
    /// One line of documentation.
    pub doc: &'static str,
}

const fn f(
    owner: &'static str,
    name: &'static str,
    params: &'static [&'static str],
    returns: &'static str,
    doc: &'static str,
) -> Entry {
    Entry {
        owner,
        name,
        item: Item::Function,
        params,
        returns,
        doc,
    }
}

const fn m(
    owner: &'static str,
    name: &'static str,
    params: &'static [&'static str],
    returns: &'static str,
    doc: &'static str,
) -> Entry {
    Entry {
        owner,
        name,
        item: Item::Method,
        params,
        returns,
        doc,
    }
}

const fn field(
    owner: &'static str,
    name: &'static str,
    ty: &'static str,
    doc: &'static str,
) -> Entry {
    Entry {
        owner,
        name,
        item: Item::Field(ty),
        params: &[],
        returns: "",
        doc,
    }
}

/// The handle classes, with their one-line docs.
pub const CLASSES: &[(&str, &str)] = &[
    (
        "Actor",
        "An articulated human in the scene (`troupe.actor`).",
    ),
    (
        "Action",
        "A running or ended action (what an action method returns).",
    ),
    ("Behavior", "A behavior (what `actor:behave` returns)."),
    ("Handler", "An event handler (what `actor:on` returns)."),
    ("Object", "A rigid object in the scene (`troupe.object`)."),
    ("Sequence", "A motion sequence (`troupe.sequence`)."),
];

/// Every documented name of the API.
pub const API: &[Entry] = &[
    // Globals (the prelude and the sandbox's additions).
    f("", "wait", &["seconds?: number"], "", "Yields until `seconds` of simulated time have passed (none or 0: the next tick)."),
    f("", "wait_until", &["fn: fun(): any", "timeout?: number"], "boolean", "Yields until `fn()` is true (returns true) or `timeout` seconds passed (returns false)."),
    f("", "wait_all", &["...: Action|Action[]"], "", "Yields until every one of the actions has ended."),
    f("", "wait_any", &["...: Action|Action[]"], "Action", "Yields until one of the actions ends; returns it."),
    f("", "run", &["seconds: number"], "", "In a test: advances the simulation by `seconds`."),
    f("", "run_until", &["fn: fun(): any", "timeout?: number"], "boolean", "In a test: advances until `fn()` is true (false at the timeout)."),
    f("", "expect", &["cond: any", "message?: string"], "any", "Fails the test (or behavior) with `message` when `cond` is false or nil."),
    f("", "test", &["name: string", "fn: fun()", "opts?: { timeout?: number }"], "", "Registers a scenario test (`troupe test`); `timeout`: its own limit in simulated seconds (default `--timeout`, 120)."),
    f("", "require", &["name: string"], "any", "Loads a module from the scene's folder, else troupe's standard library (once)."),
    f("", "print", &["...: any"], "", "Logs the values with the actor's name."),
    f("", "warn", &["...: string|number"], "", "Logs the concatenated message as a warning with the actor's name."),
    // The troupe table.
    f("troupe", "actor", &["opts: ActorOptions"], "Actor", "Creates an actor: `name` (required), `template`, `height`, `mass`, `at`, `facing`, and `look` (a rigged .glb/.gltf/.vrm character to draw it as) with its `bones` map."),
    f("troupe", "object", &["opts: ObjectOptions"], "Object", "Creates a rigid object: `name`, `shape` and its sizes, `at`, `rotation`, `mass`."),
    f("troupe", "time", &[], "number", "Scene time in seconds."),
    f("troupe", "tick", &[], "integer", "Ticks done."),
    f("troupe", "seed", &[], "integer", "The run's seed (`--seed`); `math.random` is seeded from it."),
    f("troupe", "rate", &[], "number", "Ticks per second."),
    f("troupe", "sequence", &["source: string|table", "options?: { interpolation?: string }"], "Sequence", "Loads a sequence file (.trk, .bvh, .gltf) or builds one from `{ [dof] = {{t, v}, …}, loop, name, interpolation }`."),
    f("troupe", "actors", &[], "Actor[]", "Every actor, in creation order."),
    f("troupe", "get_actor", &["name: string"], "Actor?", "The actor called `name`, or nil."),
    f("troupe", "get_object", &["name: string"], "Object?", "The object called `name`, or nil."),
    f("troupe", "plan_grasp", &["actor: Actor|string", "object: Object|string", "opts?: table"], "table?, string?", "How `actor` would grasp `object` (hand, pattern, …), or nil and why it cannot."),
    f("troupe", "performer", &["opts: table"], "Actor", "An actor driven live by motion-capture devices (docs/devices.md)."),
    f("troupe", "wall", &["opts: { from: number[], to: number[], thickness?: number, height?: number }"], "integer", "Adds a wall between two floor points `{x, z}`: an obstacle to walkers (docs/navigation.md)."),
    f("troupe", "floor", &["opts: { outline: number[][], holes?: number[][][] }"], "", "Sets the walkable floor: an outline of `{x, z}` points, with holes."),
    f("troupe", "path", &["from: number[]", "to: number[]", "opts?: { radius?: number }"], "number[][]?, string?", "A path around the obstacles from `from` to `to` (`{x, z}`), or nil and why."),
    f("troupe", "deepest_overlap", &["opts?: { discs?: boolean }"], "number, string?, string?, string?, string?", "The deepest interpenetration of two actors' solids, or an actor's solid and an obstacle, now (m), with the actor, the other actor or obstacle, and the two solids' names; `{ discs = true }`: of the body discs (docs/navigation.md)."),
    f("troupe", "publish", &["key: string", "value: table|string|number|boolean"], "", "Publishes a JSON message under `key`; every subscriber (here, and elsewhere with --zenoh) gets it at the start of the next tick."),
    f("troupe", "subscribe", &["key_expression: string", "fn: fun(value: any, key: string)"], "", "Calls `fn(value, key)` with each message whose key matches (`*` one chunk, `**` any), at the start of a tick."),
    f("troupe", "vmc_out", &["opts: { actor?: Actor|string, to: string, rate?: number }"], "", "Streams an actor's motion over VMC to `to` (host:port) at `rate` frames per second of scene time (docs/devices.md, \"VMC\")."),
    f("troupe.devices", "spacemouse", &["opts: table"], "string", "Moves an object with a SpaceMouse (live, relayed or replayed); returns the device's name."),
    f("troupe.devices", "glove", &["performer: Actor|string"], "integer[]?", "The latest raw glove sensor values, or nil."),
    f("troupe.devices", "hand", &["performer: Actor|string"], "table<string, number>", "The glove's hand targets by DOF name."),
    f("troupe.devices", "hand_state", &["performer: Actor|string", "hand?: string"], "string, string?", "The gloved hand's grasp state and the object it holds."),
    f("troupe.devices", "health", &["name: Actor|string"], "table", "A device's state and counters."),
    f("troupe.devices", "calibrate", &["performer: Actor|string"], "", "Recalibrates a performer at the start of the next tick."),
    f("troupe.devices", "is_calibrated", &["performer: Actor|string"], "boolean", "Whether a performer is calibrated."),
    f("troupe.devices", "on_gesture", &["performer: Actor|string", "fn: fun(performer: string, gesture: string, previous: string?)"], "", "Calls `fn` (with the performer's name) when the performer's held gesture changes."),
    f("troupe.devices", "buttons", &["pattern?: string"], "table<string, boolean>", "The latest state of every matching button (`Wand0.*`), down = true."),
    f("troupe.devices", "analogs", &["pattern?: string"], "table<string, number>", "The latest value of every matching analog channel."),
    f("troupe.devices", "on_button", &["pattern: string?", "fn: fun(name: string, down: boolean, performer: string)"], "", "Calls `fn` (with the performer's name) for each change of a matching button."),
    f("troupe.devices", "on_analog", &["pattern: string?", "fn: fun(name: string, value: number, performer: string)"], "", "Calls `fn` (with the performer's name) for each new value of a matching analog channel."),
    f("troupe.devices", "train_gestures", &["performer: Actor|string", "examples: table<string, string>"], "", "Trains the gesture recogniser from recorded glove examples."),
    // Actors.
    field("Actor", "name", "string", "The actor's unique name."),
    field("Actor", "template", "string", "Its body template (`adult`, `child`)."),
    field("Actor", "height", "number", "Its standing height in metres."),
    m("Actor", "behave", &["fn: fun(self: Actor)"], "Behavior", "Gives the actor a behavior (a coroutine started on the next tick); returns its handle."),
    m("Actor", "on", &["event: ActionEvent", "fn: fun(action: Action)"], "Handler", "Calls `fn` on the tick after one of the actor's action events; returns its handle."),
    m("Actor", "position", &[], "Point", "`{x, y, z}` of the actor's root (HumanoidRoot)."),
    m("Actor", "joint_position", &["joint: string"], "Point", "`{x, y, z}` of a joint."),
    m("Actor", "dof", &["name: string"], "number", "A DOF's value."),
    m("Actor", "dofs", &["scope: string"], "string[]", "The DOF names of a scope, in order."),
    m("Actor", "holding", &[], "Object[]", "The objects the actor holds."),
    m("Actor", "actions", &[], "Action[]", "The actor's actions that have not ended."),
    m("Actor", "pose", &["values: table<string, number>"], "", "Sets DOFs directly (clamped to their limits)."),
    m("Actor", "set", &["settings: { self_collision?: boolean }"], "", "Changes the actor's settings."),
    m("Actor", "behavior_status", &[], "string", "`running` while any behavior runs, then `failed` if one failed, else `done`; `none`."),
    m("Actor", "behavior_error", &[], "string?", "The first failure message of its behaviors, or nil."),
    m("Actor", "inverse_dynamics", &["opts: table"], "table", "Joint torques for a motion (q, qd, qdd)."),
    m("Actor", "forward_dynamics", &["opts: table"], "table", "Accelerations for torques (q, qd, tau)."),
    m("Actor", "play", &["sequence: Sequence|string", "opts?: PlayOptions"], "Action", "Plays a sequence (or a motion file) on the actor."),
    m("Actor", "simulate", &["opts?: SimulateOptions"], "Action", "Physically simulates the actor's scope (falls, pushes)."),
    m("Actor", "servo", &["opts: ServoOptions"], "Action", "Holds a posture with PD control under gravity."),
    m("Actor", "track", &["opts: TrackOptions"], "Action", "Follows a sequence with PD control under gravity."),
    m("Actor", "reach", &["opts: ReachOptions"], "Action", "Reaches a hand to a target (point, object, joint)."),
    m("Actor", "ik", &["opts: IkOptions"], "Action", "Moves any effector to a point by inverse kinematics."),
    m("Actor", "look_at", &["opts: LookAtOptions"], "Action", "Turns the eyes, head and neck toward a target."),
    m("Actor", "walk", &["opts: WalkOptions"], "Action", "Walks around obstacles to a point, an object or an actor, along a path, at a velocity, or following an actor."),
    m("Actor", "grasp", &["opts: GraspOptions"], "Action", "Grasps an object."),
    m("Actor", "release", &["opts: ReleaseOptions"], "Action", "Releases a held object."),
    m("Actor", "place", &["opts: PlaceOptions"], "Action", "Puts a held object down at a place."),
    m("Actor", "manipulate", &["opts: ManipulateOptions"], "Action", "Moves a held object through keyed poses."),
    m("Actor", "give", &["opts: GiveOptions"], "Action", "Hands an object to another actor."),
    m("Actor", "receive", &["opts: ReceiveOptions"], "Action", "Takes an object another actor offers."),
    m("Actor", "hold_hand", &["opts: HoldHandOptions"], "Action", "Holds another actor's hand."),
    m("Actor", "shake_hands", &["opts: ShakeHandsOptions"], "Action", "Shakes hands with another actor."),
    m("Actor", "capture", &["opts: CaptureOptions"], "Action", "Drives the actor from a performer's live capture."),
    // Actions.
    field("Action", "id", "integer", "The action's number."),
    field("Action", "status", "ActionStatus", "Where it is in its life (changes when the scene steps)."),
    field("Action", "kind", "string", "The kind of motion (`keyframe`, `walk`, …)."),
    field("Action", "mode", "string", "Its priority mode."),
    field("Action", "weight", "number", "Its weight."),
    field("Action", "error", "string?", "Why it was cancelled or failed, else nil."),
    field("Action", "dofs", "integer", "How many DOFs its scope holds."),
    field("Action", "yielded", "integer", "How many DOFs of its scope it gave up to others (`action_narrowed`)."),
    field("Action", "detours", "integer", "How many temporary goals its hand path took round other actors' bodies and obstacles (a `reach`, `grasp`, `give` or `receive`; docs/navigation.md)."),
    m("Action", "stop", &[], "", "Ends the action gracefully (a walk comes to a stop); it completes."),
    m("Action", "wait", &[], "ActionStatus", "Yields until the action ends; returns its final status."),
    m("Action", "cancel", &[], "", "Cancels the action (a running one eases out)."),
    // Behaviors and handlers.
    field("Behavior", "status", "BehaviorStatus", "`running`, `done`, `failed` or `stopped`."),
    field("Behavior", "error", "string?", "The failure message with its file:line, else nil."),
    field("Behavior", "actor", "Actor?", "The actor it belongs to (nil for a test)."),
    m("Behavior", "stop", &[], "", "Stops the behavior: it is not resumed again and ends `stopped`."),
    m("Behavior", "wait", &[], "BehaviorStatus, string?", "Yields until the behavior has ended; returns its status and error."),
    m("Handler", "off", &[], "boolean", "Removes the handler; false when it was already off."),
    // Objects and sequences.
    field("Object", "name", "string", "The object's unique name."),
    field("Object", "shape", "string", "`box`, `sphere`, `cylinder`, `frustum` or `ellipsoid`."),
    field("Object", "mass", "number", "Its mass in kg."),
    field("Object", "holder", "Actor?", "The actor holding it, or nil."),
    m("Object", "position", &[], "Point", "`{x, y, z}` of its centre."),
    m("Object", "up", &[], "Vec3", "The world direction of its own up (+Y) axis: `{0, 1, 0}` while it stands upright."),
    field("Sequence", "name", "string", "Its name (`sequence@file:line` when made inline without one)."),
    field("Sequence", "duration", "number", "Its length in seconds."),
    field("Sequence", "loop", "boolean", "Whether it loops."),
    m("Sequence", "dofs", &[], "string[]", "The DOFs it drives."),
    m("Sequence", "value", &["dof: string", "time: number"], "number", "A track's value at `time`."),
    m("Sequence", "interpolation", &["dof: string"], "string", "How a track interpolates: cubic, hermite, linear or step."),
];

/// An action kind's method, its option class, and each option's name and EmmyLua type.
pub type KindOptions = (
    &'static str,
    &'static str,
    &'static [(&'static str, &'static str)],
);

/// The options of each action method beyond the common ones (`ActionOptions`): the kind,
/// its option class, and each option's name and EmmyLua type. A test holds them to the
/// options each builder accepts (the list its "unknown option" error gives).
pub const KIND_OPTIONS: &[KindOptions] = &[
    (
        "play",
        "PlayOptions",
        &[("loop", "boolean"), ("part", "string")],
    ),
    (
        "simulate",
        "SimulateOptions",
        &[
            ("gravity", "Vec3"),
            ("floor", "boolean"),
            ("damping", "number"),
            ("small_time_step", "number"),
            ("time_step", "number"),
            ("limits", "boolean"),
            ("push", "any"),
        ],
    ),
    (
        "servo",
        "ServoOptions",
        &[
            ("gravity", "Vec3"),
            ("floor", "boolean"),
            ("damping", "number"),
            ("small_time_step", "number"),
            ("time_step", "number"),
            ("limits", "boolean"),
            ("target", "any"),
            ("kp", "number"),
            ("kd", "number"),
            ("gravity_compensation", "boolean"),
        ],
    ),
    (
        "track",
        "TrackOptions",
        &[
            ("gravity", "Vec3"),
            ("floor", "boolean"),
            ("damping", "number"),
            ("small_time_step", "number"),
            ("time_step", "number"),
            ("limits", "boolean"),
            ("sequence", "Sequence|string"),
            ("kp", "number"),
            ("kd", "number"),
        ],
    ),
    (
        "reach",
        "ReachOptions",
        &[
            ("hand", "string"),
            ("target", "any"),
            ("orientation", "Vec3"),
            ("via", "any"),
            ("self_collision", "boolean"),
            ("detour", "boolean"),
        ],
    ),
    (
        "ik",
        "IkOptions",
        &[
            ("effector", "string"),
            ("point", "Vec3"),
            ("target", "any"),
            ("orientation", "Vec3"),
            ("via", "any"),
            ("self_collision", "boolean"),
            ("detour", "boolean"),
        ],
    ),
    ("look_at", "LookAtOptions", &[("target", "any")]),
    (
        "walk",
        "WalkOptions",
        &[
            ("to", "Vec3|Object|Actor|string"),
            ("path", "any"),
            ("velocity", "any"),
            ("follow", "Sequence|string"),
            ("speed", "number"),
            ("heading", "any"),
            ("step_length", "number"),
            ("step_width", "number"),
            ("pelvis", "any"),
            ("arm_swing", "any"),
            ("bounce", "any"),
            ("run", "any"),
            ("arms", "any"),
            ("distance", "number"),
            ("patience", "number"),
        ],
    ),
    (
        "grasp",
        "GraspOptions",
        &[
            ("object", "Object|string"),
            ("hand", "string"),
            ("pattern", "string"),
            ("detour", "boolean"),
        ],
    ),
    ("release", "ReleaseOptions", &[("object", "Object|string")]),
    (
        "place",
        "PlaceOptions",
        &[
            ("object", "Object|string"),
            ("at", "Vec3"),
            ("rotation", "Vec3"),
        ],
    ),
    (
        "manipulate",
        "ManipulateOptions",
        &[
            ("object", "Object|string"),
            ("keys", "table|fun(t: number): any"),
        ],
    ),
    (
        "give",
        "GiveOptions",
        &[
            ("object", "Object|string"),
            ("to", "Actor|string"),
            ("hand", "string"),
            ("timeout", "number"),
            ("detour", "boolean"),
        ],
    ),
    (
        "receive",
        "ReceiveOptions",
        &[
            ("object", "Object|string"),
            ("from", "Actor|string"),
            ("hand", "string"),
            ("detour", "boolean"),
        ],
    ),
    (
        "hold_hand",
        "HoldHandOptions",
        &[
            ("other", "Actor|string"),
            ("hand", "string"),
            ("other_hand", "string"),
        ],
    ),
    (
        "shake_hands",
        "ShakeHandsOptions",
        &[
            ("other", "Actor|string"),
            ("hand", "string"),
            ("other_hand", "string"),
        ],
    ),
    ("capture", "CaptureOptions", &[]),
];

/// Aliases and option classes the entries name.
const TYPES: &str = r#"---@alias Vec3 number[]|{x: number, y: number, z: number}
---A position troupe returns: `{x, y, z}`, always three numbers.
---@alias Point [number, number, number]
---@alias ActionEvent "action_started"|"action_completed"|"action_failed"|"action_cancelled"|"action_narrowed"
---@alias ActionStatus "pending"|"initiating"|"active"|"terminating"|"completed"|"cancelled"|"failed"
---@alias BehaviorStatus "running"|"done"|"failed"|"stopped"

---The options of `troupe.actor`.
---@class ActorOptions
---@field name string
---@field template? string
---@field height? number
---@field mass? number
---@field at? Vec3
---@field facing? number
---@field look? string
---@field bones? table<string, string>

---The options of `troupe.object`.
---@class ObjectOptions
---@field name string
---@field shape? "box"|"sphere"|"cylinder"|"frustum"|"ellipsoid"
---@field size? Vec3
---@field radius? number
---@field height? number
---@field bottom_radius? number
---@field top_radius? number
---@field radii? Vec3
---@field at? Vec3
---@field rotation? Vec3
---@field mass? number
---@field obstacle? boolean

---The options every action method takes (docs/lua-api.md, "Actions").
---@class ActionOptions
---@field scope? string
---@field mode? string
---@field weight? number
---@field ease_in? number
---@field ease_out? number
---@field delay? number
---@field duration? number
"#;

/// The EmmyLua / LuaLS `---@meta` definition file of the whole API.
pub fn lua_defs() -> String {
    let mut out = String::from(
        "---@meta troupe\n-- The troupe Lua API, generated by `troupe lua-defs` from the API registry \
         (runtime/lua/src/reference.rs); do not edit.\n\n",
    );
    out.push_str(TYPES);
    out.push('\n');
    for (kind, class, fields) in KIND_OPTIONS {
        out.push_str(&format!(
            "---The options of `actor:{kind}`.\n---@class {class}: ActionOptions\n"
        ));
        for (name, ty) in *fields {
            out.push_str(&format!("---@field {name}? {ty}\n"));
        }
        out.push('\n');
    }
    for (class, doc) in CLASSES {
        out.push_str(&format!("---{doc}\n---@class {class}\n"));
        for e in API.iter().filter(|e| e.owner == *class) {
            if let Item::Field(ty) = e.item {
                out.push_str(&format!("---@field {} {ty} {}\n", e.name, e.doc));
            }
        }
        out.push_str(&format!("local {class} = {{}}\n\n"));
    }
    out.push_str("---The troupe API.\ntroupe = {}\n\n---Live devices and performers.\ntroupe.devices = {}\n\n");
    for e in API.iter().filter(|e| !matches!(e.item, Item::Field(_))) {
        out.push_str(&format!("---{}\n", e.doc));
        let mut names = Vec::new();
        for p in e.params {
            let (name, ty) = p.split_once(": ").unwrap_or((p, "any"));
            out.push_str(&format!("---@param {name} {ty}\n"));
            names.push(name.trim_end_matches('?'));
        }
        if !e.returns.is_empty() {
            out.push_str(&format!("---@return {}\n", e.returns));
        }
        let sep = if e.item == Item::Method { ":" } else { "." };
        let path = if e.owner.is_empty() {
            e.name.to_string()
        } else {
            format!("{}{sep}{}", e.owner, e.name)
        };
        out.push_str(&format!("function {path}({}) end\n\n", names.join(", ")));
    }
    out
}
