//! The scene: actors, objects and their actions, stepped tick by tick.

use crate::action::{ActionId, ActionInfo, ActionSpec, Ending, Event, Generator, Status};
use crate::blackboard::{Blackboard, Note, Notes, Offer, SignalId};
use crate::bodies::{CrowdEntry, Held};
use crate::error::{Error, Result};
use crate::holding::{self, HoldRequest, Holder};
use crate::input_pose::InputPose;
use crate::mailbox::Mailbox;
use crate::parallel::WorkerPool;
use crate::profile::StepProfile;
use crate::scheduler::{Action, ActorRuntime, TickClock};
use crate::world::{ActorInfo, Object, World};
use glam::{DQuat, DVec2, DVec3};
use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};
use std::sync::Arc;
use std::time::Instant;
use troupe_body::character::{Character, Dressing};
use troupe_body::sensors::Side;
use troupe_body::skeleton::Skeleton;
use troupe_body::solid::Shape;
use troupe_body::state::ActorState;
use troupe_body::template::{template, TemplateParams};

/// A map keyed by action id. Scripts look actions up every tick (their wait
/// conditions), and ids are small sequential integers, so a multiplicative hash serves
/// better than the default DoS-resistant SipHash (which cost 4 % of a 1,000-actor tick).
type IdMap<V> = HashMap<ActionId, V, BuildHasherDefault<IdHasher>>;

/// Fibonacci hashing of a `u64` id: spreads sequential ids over all bits.
#[derive(Default)]
struct IdHasher(u64);

impl Hasher for IdHasher {
    fn finish(&self) -> u64 {
        self.0
    }

    fn write(&mut self, bytes: &[u8]) {
        // Only `write_u64` is used for ids; other input still hashes, byte by byte.
        for &b in bytes {
            self.write_u64(u64::from(b) ^ self.0.rotate_left(8));
        }
    }

    fn write_u64(&mut self, n: u64) {
        self.0 = n.wrapping_mul(0x9E37_79B9_7F4A_7C15);
    }
}

/// How a scene runs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SceneConfig {
    /// Ticks per second (default 100).
    pub rate: f64,
    /// Worker threads for stepping actors (default 1).
    pub threads: usize,
    /// Seed for anything random in the scene (scripts, benchmarks).
    pub seed: u64,
}

impl Default for SceneConfig {
    fn default() -> Self {
        SceneConfig {
            rate: 100.0,
            threads: 1,
            seed: 0,
        }
    }
}

/// How to make an actor.
#[derive(Clone, Debug, PartialEq)]
pub struct ActorDesc {
    /// Unique name.
    pub name: String,
    /// Body template name.
    pub template: String,
    /// Height in metres; the template's default when `None`.
    pub height: Option<f64>,
    /// Mass in kilograms; the template's default when `None`.
    pub mass: Option<f64>,
    /// Where it stands on the floor (x, z; y is ignored).
    pub at: DVec3,
    /// Heading in degrees about +Y; 0 faces +Z.
    pub facing_degrees: f64,
}

impl ActorDesc {
    /// An adult of default size at the origin facing +Z.
    pub fn new(name: impl Into<String>) -> Self {
        ActorDesc {
            name: name.into(),
            template: "adult".into(),
            height: None,
            mass: None,
            at: DVec3::ZERO,
            facing_degrees: 0.0,
        }
    }
}

/// The part of each actor that the parallel step writes.
struct ActorWork {
    runtime: ActorRuntime,
    next: ActorState,
}

/// A set of actors and objects with their actions; [`Scene::step`] advances one tick.
pub struct Scene {
    config: SceneConfig,
    tick: u64,
    actors: Vec<ActorInfo>,
    states: Vec<ActorState>,
    work: Vec<ActorWork>,
    objects: Vec<Object>,
    holders: Vec<Option<Holder>>,
    /// The objects held, in object order, with their holders (see [`World::held`]).
    held: Vec<(usize, Holder)>,
    board: Blackboard,
    input_poses: Vec<Option<InputPose>>,
    next_action: u64,
    action_owner: IdMap<usize>,
    ended: IdMap<ActionInfo>,
    events: Vec<Event>,
    pool: WorkerPool,
    profiling: bool,
    profile: StepProfile,
    skeleton_cache: Vec<(String, TemplateParams, Arc<Skeleton>)>,
    mailbox: Mailbox,
    space: troupe_nav::Space,
    obstacle_flags: Vec<Option<bool>>,
    crowd: troupe_nav::Crowd,
    /// Per actor, whether it has a walk that has not ended (see [`World::walking`]).
    walking: Vec<bool>,
    /// Per actor: the DOF indices of root_x and root_z.
    root_dofs: Vec<(usize, usize)>,
    /// Per actor: the joints that stretch or widen its body on the floor (see
    /// [`crate::bodies::BodyJoints`]).
    body_joints: Vec<crate::bodies::BodyJoints>,
    /// Per actor: the user's character it is dressed in, if any (drawn instead of the
    /// generated skin; it changes nothing in the simulation).
    looks: Vec<Option<Arc<Dressing>>>,
}

impl Scene {
    /// An empty scene.
    pub fn new(config: SceneConfig) -> Result<Scene> {
        if !(config.rate.is_finite() && config.rate > 0.0 && config.rate <= 10_000.0) {
            return Err(Error::invalid_value(
                "tick rate",
                config.rate,
                "0 < rate ≤ 10000 Hz",
            ));
        }
        if config.threads == 0 || config.threads > 256 {
            return Err(Error::invalid_value(
                "threads",
                config.threads as f64,
                "1 to 256",
            ));
        }
        Ok(Scene {
            config,
            tick: 0,
            actors: Vec::new(),
            states: Vec::new(),
            work: Vec::new(),
            objects: Vec::new(),
            holders: Vec::new(),
            held: Vec::new(),
            board: Blackboard::default(),
            input_poses: Vec::new(),
            next_action: 1,
            action_owner: IdMap::default(),
            ended: IdMap::default(),
            events: Vec::new(),
            pool: WorkerPool::new(config.threads),
            profiling: false,
            profile: StepProfile::default(),
            skeleton_cache: Vec::new(),
            mailbox: Mailbox::default(),
            space: troupe_nav::Space::default(),
            obstacle_flags: Vec::new(),
            crowd: troupe_nav::Crowd::default(),
            walking: Vec::new(),
            root_dofs: Vec::new(),
            body_joints: Vec::new(),
            looks: Vec::new(),
        })
    }

    /// Messages between scenes and tools (`troupe.publish`, `troupe.subscribe`).
    pub fn mailbox(&self) -> &Mailbox {
        &self.mailbox
    }

    /// The mailbox, to publish, subscribe and deliver.
    pub fn mailbox_mut(&mut self) -> &mut Mailbox {
        &mut self.mailbox
    }

    /// The configuration.
    pub fn config(&self) -> SceneConfig {
        self.config
    }
    /// Seconds per tick.
    pub fn dt(&self) -> f64 {
        1.0 / self.config.rate
    }
    /// Ticks done so far.
    pub fn tick(&self) -> u64 {
        self.tick
    }
    /// Scene time in seconds.
    pub fn time(&self) -> f64 {
        self.tick as f64 / self.config.rate
    }
    /// The actors' fixed descriptions, by index.
    pub fn actors(&self) -> &[ActorInfo] {
        &self.actors
    }
    /// The actors' states at the end of the last tick, by index.
    pub fn states(&self) -> &[ActorState] {
        &self.states
    }
    /// The objects, by index.
    pub fn objects(&self) -> &[Object] {
        &self.objects
    }
    /// Mutable access to the objects (for drivers and attachments between ticks).
    pub fn objects_mut(&mut self) -> &mut [Object] {
        &mut self.objects
    }
    /// The shared space: walls and the walkable floor (see [`crate::space`]).
    pub fn space(&self) -> &troupe_nav::Space {
        &self.space
    }

    /// The shared space, to change.
    pub(crate) fn space_mut(&mut self) -> &mut troupe_nav::Space {
        &mut self.space
    }

    /// Where every actor stands and goes, and the obstacles' footprints, from the end of
    /// the previous tick: what walkers avoid (see [`troupe_nav::Crowd`]).
    fn update_crowd(&mut self) {
        let _span = tracing::trace_span!("crowd", tick = self.tick).entered();
        let mut crowd = std::mem::take(&mut self.crowd);
        let world = self.world();
        // The footprints are made again only when a wall or an object changed. Walks that
        // go straight keep them too: where they stand at their goal is chosen clear of
        // the obstacles, from the same footprints as navigated walks.
        let current = crowd.footprints_current(
            &self.space.walls,
            (0..self.objects.len()).map(|i| world.obstacle_stamp(i)),
        );
        if !current {
            crowd.set_footprints(world.obstacles());
        }
        crowd.positions.clear();
        crowd.velocities.clear();
        crowd.facings.clear();
        crowd.feet.clear();
        crowd.soles.clear();
        crowd.bodies.clear();
        crowd.cores.clear();
        // What each holding hand holds (both hands of a two-handed hold) reaches as low as
        // its lowest point and as far as its points seen from above.
        let held: Vec<(usize, Held)> = self
            .held
            .iter()
            .flat_map(|&(o, h)| {
                let object = &self.objects[o];
                let points = troupe_nav::footprint::surface_points(
                    &object.shape,
                    object.rotation,
                    object.position,
                );
                let lowest = points.iter().map(|p| p.y).fold(f64::INFINITY, f64::min);
                let outline: Vec<DVec2> = points.iter().map(|p| DVec2::new(p.x, p.z)).collect();
                h.wrists().map(move |wrist| {
                    let outline = outline.clone();
                    (
                        h.actor,
                        Held {
                            wrist,
                            lowest,
                            outline,
                        },
                    )
                })
            })
            .collect();
        // Each actor's entry reads only its own posture, so the entries (about 2,000
        // instructions an actor with navigation) are found on the pool, then pushed in
        // actor order: the same crowd on any number of threads.
        let mut entries: Vec<Option<CrowdEntry>> = self.states.iter().map(|_| None).collect();
        let (states, root_dofs, body_joints) = (&self.states, &self.root_dofs, &self.body_joints);
        let (walking, radii) = (self.space.walking, &crowd.radii);
        self.pool.for_each(&mut entries, |i, entry| {
            let (state, (x, z)) = (&states[i], root_dofs[i]);
            let holds: Vec<&Held> = held.iter().filter(|h| h.0 == i).map(|h| &h.1).collect();
            *entry = Some(CrowdEntry::of(
                state,
                (state.qd[x], state.qd[z]),
                (&body_joints[i], radii[i], &holds),
                walking,
            ));
        });
        for entry in entries.into_iter().flatten() {
            crowd.feet.push(entry.feet);
            crowd.soles.push(entry.soles);
            crowd.positions.push(entry.position);
            crowd.velocities.push(entry.velocity);
            crowd.facings.push(entry.facing);
            crowd.bodies.push(entry.body);
            crowd.cores.push(entry.core);
        }
        crowd.index();
        self.crowd = crowd;
    }

    /// The crowd as of the last tick (see [`troupe_nav::Crowd`]).
    pub fn crowd(&self) -> &troupe_nav::Crowd {
        &self.crowd
    }

    /// Per object: forced obstacle or not, or `None` for "when it stands on the floor".
    pub(crate) fn obstacle_flags_mut(&mut self) -> &mut [Option<bool>] {
        &mut self.obstacle_flags
    }

    /// Status changes of the last tick, in actor order then occurrence order.
    pub fn events(&self) -> &[Event] {
        &self.events
    }
    /// The read-only world view as of the last tick.
    pub fn world(&self) -> World<'_> {
        World {
            time: self.time(),
            actors: &self.actors,
            states: &self.states,
            objects: &self.objects,
            holders: &self.holders,
            held: &self.held,
            board: &self.board,
            input_poses: &self.input_poses,
            space: &self.space,
            obstacle_flags: &self.obstacle_flags,
            crowd: &self.crowd,
            walking: &self.walking,
        }
    }

    /// What actions told one another and the observers (see [`crate::blackboard`]).
    pub fn blackboard(&self) -> &Blackboard {
        &self.board
    }

    /// A new signal for actions to raise and wait on (e.g. a give and its receive).
    pub fn new_signal(&mut self) -> SignalId {
        self.board.new_signal()
    }

    /// Raises `signal` between ticks: generators see it from the next tick on.
    pub fn raise(&mut self, signal: SignalId) {
        self.board.raise(signal, self.tick);
    }

    /// Declares that a device (a data glove) drives `actor`'s hand `side`: a giver brings
    /// objects into that hand instead of handing them over.
    pub fn declare_device_hand(&mut self, actor: usize, side: Side) -> Result<()> {
        self.actor_info(actor)?;
        self.board.add_device_hand(actor, side);
        Ok(())
    }

    /// Sets what devices ask of `actor` (the session's input phase; a performer's
    /// `capture` reads it through the world).
    pub fn set_input_pose(&mut self, actor: usize, pose: InputPose) -> Result<()> {
        let info = self.actor_info(actor)?;
        let n = info.skeleton.dof_count();
        if pose.q.len() != n || pose.mask.len() != n {
            return Err(Error::Invalid(format!(
                "input pose of `{}`: {} values and {} mask entries for {n} DOFs",
                info.name,
                pose.q.len(),
                pose.mask.len()
            )));
        }
        if self.input_poses.len() < self.actors.len() {
            self.input_poses.resize(self.actors.len(), None);
        }
        self.input_poses[actor] = Some(pose);
        Ok(())
    }

    /// What devices ask of `actor`, if a device drives it.
    pub fn input_pose(&self, actor: usize) -> Option<&InputPose> {
        self.input_poses.get(actor).and_then(Option::as_ref)
    }

    /// Opens an offer of an object to a device-driven hand (see [`Offer`]).
    pub fn open_offer(&mut self, offer: Offer) -> Result<()> {
        self.actor_info(offer.giver)?;
        self.actor_info(offer.receiver)?;
        if offer.object >= self.objects.len() {
            return Err(Error::UnknownObject(format!("#{}", offer.object)));
        }
        self.board.open_offer(offer);
        Ok(())
    }

    /// Actor `actor`, or an error naming the index.
    fn actor_info(&self, actor: usize) -> Result<&ActorInfo> {
        self.actors
            .get(actor)
            .ok_or_else(|| Error::UnknownActor(format!("#{actor}")))
    }

    /// Who holds object `object`, if anyone.
    pub fn holder(&self, object: usize) -> Option<Holder> {
        self.holders.get(object).copied().flatten()
    }

    /// The objects `actor` holds, in object order.
    pub fn held_by(&self, actor: usize) -> Vec<usize> {
        self.held
            .iter()
            .filter(|(_, h)| h.actor == actor)
            .map(|&(object, _)| object)
            .collect()
    }

    /// After holders changed: moves the held objects to their hands and lists them again
    /// (see [`World::held`]).
    fn holders_changed(&mut self) {
        holding::follow(&self.holders, &mut self.objects, &self.states);
        holding::list_held(&self.holders, &mut self.held);
    }

    /// Applies an attach/release/place request as if `actor`'s action had made it, then
    /// moves held objects; returns whether it took effect (for tools and tests).
    pub fn request_hold(&mut self, actor: usize, request: HoldRequest) -> bool {
        let done = holding::apply(
            actor,
            request,
            &mut self.holders,
            &mut self.objects,
            &self.states,
        );
        self.holders_changed();
        done
    }

    /// The index of the actor called `name`.
    pub fn actor_index(&self, name: &str) -> Result<usize> {
        self.actors
            .iter()
            .position(|a| a.name == name)
            .ok_or_else(|| Error::UnknownActor(name.to_string()))
    }

    /// The index of the object called `name`.
    pub fn object_index(&self, name: &str) -> Result<usize> {
        self.objects
            .iter()
            .position(|o| o.name == name)
            .ok_or_else(|| Error::UnknownObject(name.to_string()))
    }

    /// Adds an actor built from a template; actors of equal template and parameters share
    /// one skeleton.
    pub fn add_actor(&mut self, desc: &ActorDesc) -> Result<usize> {
        self.add_dressed_actor(desc, None)
    }

    /// The skeleton an actor of `desc` would have, after the checks that adding it makes
    /// (name given and unused, finite place and facing, a known template); adds nothing.
    /// A performer opens its devices with it before its actor exists, so that a device
    /// that fails leaves no actor behind.
    pub fn skeleton_for(&mut self, desc: &ActorDesc) -> Result<(Arc<Skeleton>, TemplateParams)> {
        check_name("an actor", &desc.name)?;
        if self.actors.iter().any(|a| a.name == desc.name) {
            return Err(Error::Duplicate {
                what: "actor",
                name: desc.name.clone(),
            });
        }
        if !desc.at.is_finite() || !desc.facing_degrees.is_finite() {
            return Err(Error::Invalid(format!(
                "actor `{}`: position and facing must be finite numbers",
                desc.name
            )));
        }
        let t = template(&desc.template)?;
        let params = TemplateParams {
            height: desc.height.unwrap_or(t.default_height),
            mass: desc.mass.unwrap_or(t.default_mass),
        };
        let cached = self
            .skeleton_cache
            .iter()
            .find(|(n, p, _)| *n == desc.template && *p == params);
        let skeleton = match cached {
            Some((_, _, s)) => s.clone(),
            None => {
                let s = Arc::new(t.instantiate(params)?);
                self.skeleton_cache
                    .push((desc.template.clone(), params, s.clone()));
                s
            }
        };
        Ok((skeleton, params))
    }

    /// Adds an actor as [`Scene::add_actor`] does, dressed in a user's rigged character
    /// fitted to its skeleton and height when `look` is given (drawn instead of the
    /// generated skin; it changes nothing in the simulation). A character that does not
    /// fit is an error naming what it lacks, and no actor is added.
    pub fn add_dressed_actor(
        &mut self,
        desc: &ActorDesc,
        look: Option<&Character>,
    ) -> Result<usize> {
        let (skeleton, params) = self.skeleton_for(desc)?;
        let look = match look {
            Some(character) => Some(Arc::new(character.dress(&skeleton, params.height)?)),
            None => None,
        };
        let mut q = vec![0.0; skeleton.dof_count()];
        q[skeleton.dof("root_x")?] = desc.at.x;
        q[skeleton.dof("root_z")?] = desc.at.z;
        q[skeleton.dof("root_yaw")?] = desc.facing_degrees.to_radians();
        self.root_dofs
            .push((skeleton.dof("root_x")?, skeleton.dof("root_z")?));
        self.crowd.radii.push(troupe_nav::body_radius(&skeleton));
        let state = ActorState::new(&skeleton, q);
        self.body_joints
            .push(crate::bodies::BodyJoints::new(&skeleton, &state.globals));
        self.work.push(ActorWork {
            runtime: ActorRuntime::default(),
            next: state.clone(),
        });
        self.states.push(state);
        self.actors.push(ActorInfo {
            name: desc.name.clone(),
            template: desc.template.clone(),
            params,
            skeleton,
        });
        self.looks.push(look);
        Ok(self.actors.len() - 1)
    }

    /// The character actor `actor` is dressed in, if any (see [`Scene::add_dressed_actor`]).
    pub fn look(&self, actor: usize) -> Option<&Arc<Dressing>> {
        self.looks.get(actor)?.as_ref()
    }

    /// Adds a rigid object.
    pub fn add_object(&mut self, object: Object) -> Result<usize> {
        check_name("an object", &object.name)?;
        if self.objects.iter().any(|o| o.name == object.name) {
            return Err(Error::Duplicate {
                what: "object",
                name: object.name,
            });
        }
        object.shape.validate()?;
        if !(object.mass.is_finite() && object.mass > 0.0) {
            return Err(Error::invalid_value(
                "object mass",
                object.mass,
                "a finite mass > 0 kg",
            ));
        }
        if !object.position.is_finite() || !object.rotation.is_finite() {
            return Err(Error::Invalid(format!(
                "object `{}`: position and rotation must be finite",
                object.name
            )));
        }
        self.objects.push(object);
        self.holders.push(None);
        self.obstacle_flags.push(None);
        Ok(self.objects.len() - 1)
    }

    /// Builds an object of `shape` at `position`.
    pub fn object(name: impl Into<String>, shape: Shape, position: DVec3, mass: f64) -> Object {
        Object {
            name: name.into(),
            shape,
            position,
            rotation: DQuat::IDENTITY,
            mass,
        }
    }

    /// Sets DOFs of an actor directly (value and held value); an action driving them takes
    /// over on the next tick. Values are clamped to the DOF limits.
    pub fn set_dofs(&mut self, actor: usize, values: &[(usize, f64)]) -> Result<()> {
        let info = self.actor_info(actor)?;
        let skeleton = info.skeleton.clone();
        let state = &mut self.states[actor];
        for &(d, v) in values {
            let dof = skeleton.dofs().get(d).ok_or_else(|| {
                Error::Body(troupe_body::Error::UnknownDof {
                    name: format!("#{d}"),
                    skeleton: skeleton.name().to_string(),
                    hint: String::new(),
                })
            })?;
            if !v.is_finite() {
                return Err(Error::invalid_value(dof.name.clone(), v, "a finite number"));
            }
            state.q[d] = dof.clamp(v);
            state.held[d] = state.q[d];
        }
        state.update_kinematics(&skeleton);
        Ok(())
    }

    /// Creates an action for `actor`; it waits as `pending` until the scheduler admits it.
    /// A refused action has ended before it began: its generator's end notes (a partner
    /// waiting on it) are posted at once.
    pub fn start_action(
        &mut self,
        actor: usize,
        spec: ActionSpec,
        mut generator: Box<dyn Generator>,
    ) -> Result<ActionId> {
        if let Err(e) = self.check_action(actor, &spec) {
            let mut notes = Notes::default();
            let reason = e.to_string();
            generator.end(
                &Ending {
                    status: Status::Failed,
                    reason: Some(&reason),
                },
                &mut notes,
            );
            // Signals go out; notes about an actor that does not exist do not.
            let mut notes = notes.take();
            if actor >= self.actors.len() {
                notes.retain(|n| matches!(n, Note::Raise(_)));
            }
            self.board.apply(actor, self.tick, notes);
            return Err(e);
        }
        let id = ActionId(self.next_action);
        self.next_action += 1;
        let begin = self.time() + spec.delay;
        self.work[actor]
            .runtime
            .push(Action::new(id, spec, begin, generator));
        self.action_owner.insert(id, actor);
        Ok(id)
    }

    /// Whether `actor` may run an action of `spec`.
    fn check_action(&self, actor: usize, spec: &ActionSpec) -> Result<()> {
        let info = self.actor_info(actor)?;
        spec.validate()?;
        if spec.scope.iter().any(|d| d >= info.skeleton.dof_count()) {
            return Err(Error::Invalid(format!(
                "{} action: scope names DOFs the actor `{}` does not have",
                spec.kind, info.name
            )));
        }
        Ok(())
    }

    /// Asks an action to stop: a pending one is cancelled on the next tick, a running one
    /// winds down if its generator can (a walk stops well, see [`Scene::stop`]) or eases
    /// out, and ends `cancelled`. Cancelling an ended action does nothing.
    pub fn cancel(&mut self, id: ActionId) -> Result<()> {
        if let Some(a) = self.unfinished_action(id)? {
            a.cancel_requested = true;
        }
        Ok(())
    }

    /// Asks an action to finish gracefully: a running one whose generator can end its
    /// motion by itself (a walk slows down and puts both feet down) does so at full
    /// weight, any other eases out; either ends `completed`. A pending one is cancelled on
    /// the next tick. Stopping an ended action does nothing.
    pub fn stop(&mut self, id: ActionId) -> Result<()> {
        if let Some(a) = self.unfinished_action(id)? {
            a.stop_requested = true;
        }
        Ok(())
    }

    /// A known action that has not ended (`None` once it has), or an error for an id the
    /// scene never made.
    fn unfinished_action(&mut self, id: ActionId) -> Result<Option<&mut Action>> {
        let actor = *self
            .action_owner
            .get(&id)
            .ok_or_else(|| Error::Invalid(format!("no action {id}")))?;
        Ok(self.work[actor]
            .runtime
            .actions
            .iter_mut()
            .find(|a| a.id == id))
    }

    /// The status of an action, without copying its record (for wait conditions checked
    /// every tick).
    pub fn action_status(&self, id: ActionId) -> Option<Status> {
        match self.find_action(id)? {
            Ok((_, a)) => Some(a.status),
            Err(info) => Some(info.status),
        }
    }

    /// The current record of an action.
    pub fn action(&self, id: ActionId) -> Option<ActionInfo> {
        match self.find_action(id)? {
            Ok((actor, a)) => Some(a.info(actor)),
            Err(info) => Some(info.clone()),
        }
    }

    /// A known action: still with its actor (and which), or its final record.
    fn find_action(
        &self,
        id: ActionId,
    ) -> Option<std::result::Result<(usize, &Action), &ActionInfo>> {
        let actor = *self.action_owner.get(&id)?;
        match self.work[actor].runtime.actions.iter().find(|a| a.id == id) {
            Some(a) => Some(Ok((actor, a))),
            None => self.ended.get(&id).map(Err),
        }
    }

    /// The actions of `actor` that have not ended, in creation order.
    pub fn actions_of(&self, actor: usize) -> Vec<ActionInfo> {
        self.work
            .get(actor)
            .map(|w| w.runtime.actions.iter().map(|a| a.info(actor)).collect())
            .unwrap_or_default()
    }

    /// Every running action's plan and avoidance, as its generator reports it (walks
    /// do, see [`crate::Generator::navigation`]), with the actor's index, in actor order.
    pub fn navigation(&self) -> Vec<(usize, crate::space::Navigation)> {
        self.work
            .iter()
            .enumerate()
            .flat_map(|(actor, w)| {
                w.runtime
                    .actions
                    .iter()
                    .filter(|a| a.status.is_running())
                    .filter_map(move |a| Some((actor, a.generator.navigation()?)))
            })
            .collect()
    }

    /// Forgets the records of actions that ended before `before` (scene time) unless
    /// `keep(id)` says someone still refers to them; returns how many were forgotten.
    /// Long runs start many actions: this keeps memory bounded.
    pub fn forget_ended_actions(&mut self, before: f64, keep: impl Fn(ActionId) -> bool) -> usize {
        let old: Vec<ActionId> = self
            .ended
            .iter()
            .filter(|(id, info)| info.ended_at.is_some_and(|t| t < before) && !keep(**id))
            .map(|(id, _)| *id)
            .collect();
        for id in &old {
            self.ended.remove(id);
            self.action_owner.remove(id);
        }
        old.len()
    }

    /// Whether any action of any actor has not ended.
    pub fn has_unfinished_actions(&self) -> bool {
        self.work.iter().any(|w| !w.runtime.actions.is_empty())
    }

    /// Fixes how many actors a worker claims at a time (`None`: sized by the crowd).
    /// Tests set 1 so that even two actors are stepped on two threads.
    pub fn set_chunk_size(&mut self, actors: Option<usize>) {
        self.pool.set_chunk(actors);
    }

    /// Switches per-phase timing of [`Scene::step`] on or off (off by default).
    pub fn set_profiling(&mut self, on: bool) {
        self.profiling = on;
    }

    /// The phase timings gathered since the last call, which resets them.
    pub fn take_profile(&mut self) -> StepProfile {
        std::mem::take(&mut self.profile)
    }

    /// Generator writes refused so far because they fell outside their action's scope.
    pub fn refused_writes(&self) -> u64 {
        self.work.iter().map(|w| w.runtime.refused_writes).sum()
    }

    /// Advances one tick: every actor is stepped (in parallel when threads > 1) against
    /// the previous tick's world, then the new states are published.
    pub fn step(&mut self) -> &[Event] {
        self.tick += 1;
        let clock = TickClock {
            tick: self.tick,
            time: self.time(),
            dt: self.dt(),
            profile: self.profiling,
        };
        let started = self.profiling.then(Instant::now);
        self.update_crowd();
        self.walking.clear();
        self.walking.extend(self.work.iter().map(|w| {
            w.runtime
                .actions
                .iter()
                .any(|a| a.spec.kind == "walk" && !a.status.is_final())
        }));
        {
            let _span = tracing::trace_span!("step_actors", tick = self.tick).entered();
            let world = World {
                time: clock.time - clock.dt,
                actors: &self.actors,
                states: &self.states,
                objects: &self.objects,
                holders: &self.holders,
                held: &self.held,
                board: &self.board,
                input_poses: &self.input_poses,
                space: &self.space,
                obstacle_flags: &self.obstacle_flags,
                crowd: &self.crowd,
                walking: &self.walking,
            };
            let actors = &self.actors;
            let states = &self.states;
            self.pool.for_each(&mut self.work, |i, w| {
                let skeleton = &actors[i].skeleton;
                w.runtime
                    .tick(i, skeleton, &world, &states[i], &mut w.next, clock);
            });
        }
        let joined = self.profiling.then(Instant::now);
        let _span = tracing::trace_span!("publish", tick = self.tick).entered();
        self.events.clear();
        for (i, w) in self.work.iter_mut().enumerate() {
            std::mem::swap(&mut self.states[i], &mut w.next);
            self.events.extend(w.runtime.events.iter().cloned());
            for info in w.runtime.ended.drain(..) {
                self.ended.insert(info.id, info);
            }
            if self.profiling {
                self.profile
                    .actors
                    .add(&std::mem::take(&mut w.runtime.phases));
            }
        }
        let published = self.profiling.then(Instant::now);
        // Tick step 6 (DESIGN.md): attachments, after every actor's forward kinematics,
        // serially in actor order so the result is independent of the thread count.
        // This tick's torques replace the last tick's on the board.
        self.board.begin_tick();
        for (i, w) in self.work.iter_mut().enumerate() {
            for r in w.runtime.hold_requests.drain(..) {
                holding::apply(i, r, &mut self.holders, &mut self.objects, &self.states);
            }
            // The blackboard too: notes in actor order, seen by everyone next tick.
            self.board
                .apply(i, self.tick, std::mem::take(&mut w.runtime.notes));
            for (stamp, note) in w.runtime.end_notes.drain(..) {
                self.board.apply(i, stamp, vec![note]);
            }
        }
        self.holders_changed();
        if let (Some(started), Some(joined), Some(published)) = (started, joined, published) {
            self.profile.step_wall += joined - started;
            self.profile.publish_wall += published - joined;
            self.profile.collision_wall += published.elapsed();
        }
        &self.events
    }
}

/// Refuses a name that is empty or that could not be part of a file name: each actor's
/// and object's name goes into the files of a recording (`rec.NAME.bvh`), where a `/`
/// wrote outside the recording's folder.
fn check_name(what: &str, name: &str) -> Result<()> {
    if name.is_empty() {
        return Err(Error::Invalid(format!("{what} needs a name")));
    }
    if let Some(c) = name
        .chars()
        .find(|c| matches!(c, '/' | '\\') || c.is_control())
    {
        return Err(Error::Invalid(format!(
            "{what}'s name `{}` holds {c:?}: names become file names (a recording's \
             `rec.NAME.bvh`), so they hold no '/', '\\' or control characters",
            name.escape_default()
        )));
    }
    Ok(())
}
