//! Publishing a scene: an [`Observer`] that encodes every tick's postures, object poses,
//! events and the messages its behaviors published (`troupe.publish`, on their own keys
//! and on `<prefix>/messages`), and hands them to a background thread that puts them on
//! Zenoh.
//!
//! The tick only encodes and queues: it never waits for the network. When the queue is
//! full (subscribers slow, a link congested) the whole tick is dropped and counted, so a
//! subscriber sees complete ticks or none; Zenoh itself drops rather than blocks
//! (`CongestionControl::Drop`) once the thread puts.

use crate::error::NetError;
use crate::keys::SceneKeys;
use crate::posture;
use crossbeam::channel::{bounded, Receiver, Sender, TrySendError};
use serde_json::json;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};
use troupe_scene::{Event, Observer, Scene};
use zenoh::pubsub::{Publisher, Subscriber};
use zenoh::qos::CongestionControl;
use zenoh::query::{Query, Queryable};
use zenoh::{Session, Wait};

/// Ticks the queue holds before ticks are dropped (0.16 s at 100 Hz).
pub const QUEUE_TICKS: usize = 16;

/// What one tick sends.
struct TickBatch {
    /// Actors and objects added since the previous batch, by name, in scene order.
    new_actors: Vec<String>,
    new_objects: Vec<String>,
    /// One posture packet per actor, in scene order.
    poses: Vec<Vec<u8>>,
    /// One JSON pose per object, in scene order.
    objects: Vec<Vec<u8>>,
    /// One JSON document per event.
    events: Vec<Vec<u8>>,
    /// Messages the script published (`troupe.publish`): key and JSON.
    messages: Vec<(String, Vec<u8>)>,
    /// The same messages as behavior messages on `<prefix>/messages`, one JSON document
    /// each (`{"tick","time","key","value"}`), beside the events.
    behavior_messages: Vec<Vec<u8>>,
    /// The tick's inputs from outside, for followers ([`ScenePublisher::replicate`]);
    /// none for the starting postures.
    inputs: Option<Vec<u8>>,
}

/// What the queryables answer: the scene's description and each actor's DOF names.
#[derive(Default)]
struct Catalog {
    scene: serde_json::Value,
    /// (dofs key, JSON document), one per actor.
    dofs: Vec<(String, Vec<u8>)>,
}

/// Publishes a scene on Zenoh under one prefix (`troupe run --zenoh`).
pub struct ScenePublisher {
    keys: SceneKeys,
    /// Keeps the session open as long as the queryables answer.
    _session: Session,
    queue: Option<Sender<TickBatch>>,
    thread: Option<JoinHandle<u64>>,
    catalog: Arc<Mutex<Catalog>>,
    _queryables: Vec<Queryable<()>>,
    await_followers: Option<Duration>,
    /// Set when a follower says hello on `<prefix>/followers/*`.
    follower_seen: Arc<AtomicBool>,
    _followers: Subscriber<()>,
    actors_seen: usize,
    objects_seen: usize,
    dropped_ticks: u64,
    published_ticks: u64,
    /// What a follower needs of each tick beyond the scene file and seed.
    replicated: Option<InputsSource>,
}

/// Gives the inputs from outside that a tick took, encoded for followers (`.rec` chunks:
/// device bytes, tick marks, messages).
pub type InputsSource = Box<dyn FnMut() -> Vec<u8> + Send>;

impl ScenePublisher {
    /// A publisher on `session` under `keys`; declares the queryables at once.
    pub fn new(session: Session, keys: SceneKeys) -> Result<ScenePublisher, NetError> {
        let catalog = Arc::new(Mutex::new(Catalog::default()));
        let mut queryables = Vec::new();
        for key in [keys.scene(), keys.all_dofs()] {
            let served = catalog.clone();
            let q = session
                .declare_queryable(key.clone())
                .callback(move |query| answer(&served, &query))
                .wait()
                .map_err(|e| NetError::Declare {
                    what: "queryable",
                    key,
                    message: e.to_string(),
                })?;
            queryables.push(q);
        }
        // Followers need every tick's inputs: this one publisher waits for the network
        // (on the publishing thread, never on the tick).
        let inputs = session
            .declare_publisher(keys.inputs())
            .congestion_control(CongestionControl::Block)
            .wait()
            .map_err(|e| NetError::Declare {
                what: "publisher",
                key: keys.inputs(),
                message: e.to_string(),
            })?;
        let follower_seen = Arc::new(AtomicBool::new(false));
        let seen = follower_seen.clone();
        let followers = session
            .declare_subscriber(keys.followers())
            .callback(move |_| seen.store(true, Ordering::Release))
            .wait()
            .map_err(|e| NetError::Declare {
                what: "subscriber",
                key: keys.followers(),
                message: e.to_string(),
            })?;
        let (tx, rx) = bounded(QUEUE_TICKS);
        let thread_session = session.clone();
        let thread_keys = keys.clone();
        let thread = std::thread::Builder::new()
            .name("zenoh-publish".into())
            .spawn(move || put_batches(&thread_session, &thread_keys, &inputs, rx))
            .map_err(|e| NetError::Open(format!("starting the publishing thread: {e}")))?;
        Ok(ScenePublisher {
            keys,
            _session: session,
            queue: Some(tx),
            thread: Some(thread),
            catalog,
            _queryables: queryables,
            await_followers: None,
            follower_seen,
            _followers: followers,
            actors_seen: 0,
            objects_seen: 0,
            dropped_ticks: 0,
            published_ticks: 0,
            replicated: None,
        })
    }

    /// Before the first tick, waits up to `timeout` for a follower to subscribe to the
    /// inputs (`--zenoh-await-followers`), so it sees the run from the start.
    pub fn await_followers(&mut self, timeout: Duration) {
        self.await_followers = Some(timeout);
    }

    /// Publishes, with each tick on `<prefix>/inputs`, what `source` gives (the inputs a
    /// follower replays: device samples with their tick marks, messages from outside).
    pub fn replicate(&mut self, source: InputsSource) {
        self.replicated = Some(source);
    }

    /// Ticks dropped because the queue was full.
    pub fn dropped_ticks(&self) -> u64 {
        self.dropped_ticks
    }

    /// Ticks handed to the publishing thread.
    pub fn published_ticks(&self) -> u64 {
        self.published_ticks
    }

    /// The keys published under.
    pub fn keys(&self) -> &SceneKeys {
        &self.keys
    }

    /// Updates what the queryables serve and returns the names added since last time
    /// (refusing names that cannot be key chunks).
    fn catch_up(&mut self, scene: &Scene) -> troupe_scene::Result<(Vec<String>, Vec<String>)> {
        let actors = &scene.actors()[self.actors_seen..];
        let objects = &scene.objects()[self.objects_seen..];
        let invalid = |e: NetError| troupe_scene::Error::Invalid(e.to_string());
        let mut catalog = self.catalog.lock().expect("catalog lock");
        for a in actors {
            let names: Vec<&str> = a.skeleton.dofs().iter().map(|d| d.name.as_str()).collect();
            let doc = json!({"actor": a.name, "template": a.template,
                             "height": a.params.height, "dofs": names});
            catalog.dofs.push((
                self.keys.dofs(&a.name).map_err(invalid)?,
                doc.to_string().into_bytes(),
            ));
        }
        for o in objects {
            self.keys.object(&o.name).map_err(invalid)?;
        }
        let config = scene.config();
        catalog.scene = json!({
            "layout": posture::VERSION,
            "rate": config.rate,
            "seed": config.seed,
            "actors": scene.actors().iter().map(|a| &a.name).collect::<Vec<_>>(),
            "objects": scene.objects().iter().map(|o| &o.name).collect::<Vec<_>>(),
        });
        self.actors_seen = scene.actors().len();
        self.objects_seen = scene.objects().len();
        Ok((
            actors.iter().map(|a| a.name.clone()).collect(),
            objects.iter().map(|o| o.name.clone()).collect(),
        ))
    }

    /// Encodes the scene as it is now and queues it; a full queue drops the tick.
    fn send(&mut self, scene: &Scene, events: &[Event]) -> troupe_scene::Result<()> {
        let (new_actors, new_objects) = self.catch_up(scene)?;
        let (tick, time) = (scene.tick(), scene.time());
        let batch = TickBatch {
            new_actors,
            new_objects,
            poses: scene
                .states()
                .iter()
                .map(|s| posture::encode(tick, time, &s.q))
                .collect(),
            objects: scene
                .objects()
                .iter()
                .map(|o| {
                    let (p, r) = (o.position, o.rotation);
                    json!({"tick": tick, "time": time,
                           "position": [p.x, p.y, p.z], "rotation": [r.w, r.x, r.y, r.z]})
                    .to_string()
                    .into_bytes()
                })
                .collect(),
            events: events.iter().map(|e| event_json(scene, e)).collect(),
            messages: scene
                .mailbox()
                .published()
                .iter()
                .map(|m| (m.key.clone(), m.value.to_string().into_bytes()))
                .collect(),
            behavior_messages: scene
                .mailbox()
                .published()
                .iter()
                .map(|m| {
                    json!({"tick": tick, "time": time, "key": m.key, "value": m.value})
                        .to_string()
                        .into_bytes()
                })
                .collect(),
            inputs: (tick > 0).then(|| {
                let mut payload = tick.to_le_bytes().to_vec();
                if let Some(source) = &mut self.replicated {
                    payload.extend(source());
                }
                payload
            }),
        };
        let Some(queue) = &self.queue else {
            return Ok(());
        };
        match queue.try_send(batch) {
            Ok(()) => self.published_ticks += 1,
            Err(TrySendError::Full(_)) => {
                if self.dropped_ticks == 0 {
                    tracing::warn!("--zenoh: the network is behind; dropping ticks (counted)");
                }
                self.dropped_ticks += 1;
            }
            Err(TrySendError::Disconnected(_)) => {
                return Err(troupe_scene::Error::Invalid(
                    "the zenoh publishing thread has stopped".into(),
                ))
            }
        }
        Ok(())
    }
}

impl Observer for ScenePublisher {
    fn name(&self) -> String {
        format!("--zenoh-prefix {}", self.keys.prefix())
    }

    fn start(&mut self, scene: &Scene) -> troupe_scene::Result<()> {
        // The starting postures, so a subscriber that joins first sees tick 0.
        self.send(scene, &[])?;
        let Some(timeout) = self.await_followers else {
            return Ok(());
        };
        let deadline = Instant::now() + timeout;
        loop {
            // A follower says hello once it has subscribed to the postures and inputs.
            if self.follower_seen.load(Ordering::Acquire) {
                return Ok(());
            }
            if Instant::now() > deadline {
                return Err(troupe_scene::Error::Invalid(format!(
                    "no follower subscribed to {} within {} s",
                    self.keys.inputs(),
                    timeout.as_secs_f64()
                )));
            }
            std::thread::sleep(Duration::from_millis(20));
        }
    }

    fn publish(&mut self, scene: &Scene, events: &[Event]) -> troupe_scene::Result<()> {
        self.send(scene, events)
    }

    fn finish(&mut self, _scene: &Scene) -> troupe_scene::Result<Option<String>> {
        // Closing the queue lets the thread put what is left and end.
        self.queue = None;
        let failed = match self.thread.take() {
            Some(t) => t.join().unwrap_or(1),
            None => 0,
        };
        let mut line = format!(
            "published {} ticks on zenoh under {}",
            self.published_ticks,
            self.keys.prefix()
        );
        if self.dropped_ticks > 0 {
            line += &format!(" ({} dropped: the network was behind)", self.dropped_ticks);
        }
        if failed > 0 {
            line += &format!(" ({failed} puts failed)");
        }
        Ok(Some(line))
    }
}

/// The JSON document of one event.
fn event_json(scene: &Scene, e: &Event) -> Vec<u8> {
    let actor = scene.actors().get(e.actor).map(|a| a.name.as_str());
    json!({
        "tick": e.tick, "time": e.time, "actor": actor, "action": e.action.0,
        "kind": e.kind, "status": e.status.name(), "reason": e.reason,
    })
    .to_string()
    .into_bytes()
}

/// Answers a query on the scene or on DOF names, from whatever the catalog holds now.
fn answer(catalog: &Mutex<Catalog>, query: &Query) {
    let catalog = catalog.lock().expect("catalog lock");
    let asked = query.key_expr().clone();
    let mut replies: Vec<(String, Vec<u8>)> = Vec::new();
    for (key, doc) in &catalog.dofs {
        if zenoh::key_expr::KeyExpr::try_from(key.as_str()).is_ok_and(|k| asked.intersects(&k)) {
            replies.push((key.clone(), doc.clone()));
        }
    }
    if replies.is_empty() && !catalog.scene.is_null() && !asked.as_str().contains("/actors/") {
        replies.push((asked.to_string(), catalog.scene.to_string().into_bytes()));
    }
    drop(catalog);
    for (key, doc) in replies {
        if let Err(e) = query.reply(key, doc).wait() {
            tracing::debug!("--zenoh: a reply to a query failed: {e}");
        }
    }
}

/// The publishing thread: declares a publisher per actor and object as they appear and
/// puts each tick's batch; returns how many puts failed.
fn put_batches(
    session: &Session,
    keys: &SceneKeys,
    inputs: &Publisher<'static>,
    queue: Receiver<TickBatch>,
) -> u64 {
    let declare = |key: String| {
        session
            .declare_publisher(key.clone())
            .congestion_control(CongestionControl::Drop)
            .wait()
            .map_err(|e| tracing::error!("--zenoh: declaring a publisher on {key}: {e}"))
            .ok()
    };
    let mut actors = Vec::new();
    let mut objects = Vec::new();
    let events = declare(keys.events());
    let behavior_messages = declare(keys.messages());
    let mut failed = 0u64;
    for batch in queue {
        // Names were checked on the tick's side; a refused one has no publisher.
        actors.extend(
            batch
                .new_actors
                .iter()
                .map(|n| keys.pose(n).ok().and_then(declare)),
        );
        objects.extend(
            batch
                .new_objects
                .iter()
                .map(|n| keys.object(n).ok().and_then(declare)),
        );
        let puts = (actors.iter().zip(batch.poses))
            .chain(objects.iter().zip(batch.objects))
            .chain(batch.events.into_iter().map(|e| (&events, e)))
            .chain((batch.behavior_messages.into_iter()).map(|m| (&behavior_messages, m)));
        for (publisher, payload) in puts {
            if let Some(p) = publisher {
                if p.put(payload).wait().is_err() {
                    failed += 1;
                }
            }
        }
        if let Some(payload) = batch.inputs {
            if inputs.put(payload).wait().is_err() {
                failed += 1;
            }
        }
        // Messages go on their own keys, which are not under the prefix (Zenoh drops
        // rather than blocks a put by default).
        for (key, payload) in batch.messages {
            if session.put(key.as_str(), payload).wait().is_err() {
                failed += 1;
            }
        }
    }
    failed
}
