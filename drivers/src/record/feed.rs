//! Replaying recorded inputs in place of live ones: each stream's bytes decoded by the
//! decoder a live device runs, its readings handed out at the ticks the recorded run took
//! them (tick marks) with the receiver clock each tick read (clock marks: VMC), and the
//! messages from outside delivered at their ticks.
//!
//! The same replay serves a `.rec` file (`troupe run --replay-devices`) and a leader's
//! stream arriving tick by tick (`troupe run --zenoh-follow`): both are `.rec` chunks.

use crate::device::protocol::Protocol;
use crate::device::reading::Reading;
use crate::record::error::RecordError;
use crate::record::file::{ChunkReader, Item, RecordedMessage, Recording};
use crate::record::replay::protocol_from_settings;
use std::collections::{HashMap, VecDeque};
use std::path::Path;
use std::sync::{Arc, Mutex};
use troupe_scene::{Input, Message, Scene};

/// One stream's readings as they are decoded, and which tick took which.
#[derive(Default)]
pub struct StreamFeed {
    /// The stream's decoder, once its header is known.
    protocol: Option<Box<dyn Protocol>>,
    /// Every reading decoded so far (its sequence number is its index), with its
    /// recorded time in seconds.
    readings: Vec<(f64, Reading)>,
    /// (ticks since the device opened, readings taken by then), in order.
    marks: VecDeque<(u64, u64)>,
    /// (ticks since the device opened, the receiver clock that tick read), in order.
    clocks: VecDeque<(u64, u64)>,
    /// The receiver clock of the newest clock mark reached.
    clock: Option<u64>,
    /// Readings handed out so far.
    next: usize,
    /// Whether readings go out by tick marks (else by recorded time).
    by_ticks: bool,
    /// Why the stream cannot be decoded, if it cannot.
    error: Option<String>,
}

impl StreamFeed {
    /// The feed of stream `stream` of a whole recording; by ticks when the recording has
    /// tick marks.
    pub(crate) fn from_recording(rec: &Recording, stream: usize) -> Result<Self, RecordError> {
        let mut feed = StreamFeed {
            protocol: Some(rec.protocol(stream)?),
            by_ticks: !rec.marks.is_empty(),
            ..StreamFeed::default()
        };
        for c in rec
            .chunks
            .iter()
            .filter(|c| usize::from(c.stream) == stream)
        {
            feed.decode(c.micros, &c.bytes);
        }
        feed.marks = (rec.marks.iter())
            .filter(|m| usize::from(m.stream) == stream)
            .map(|m| (m.tick, m.taken))
            .collect();
        feed.clocks = (rec.clocks.iter())
            .filter(|c| usize::from(c.stream) == stream)
            .map(|c| (c.tick, c.micros))
            .collect();
        Ok(feed)
    }

    fn decode(&mut self, micros: u64, bytes: &[u8]) {
        // The conversion a live VMC listener makes too: the same seconds, bit for bit.
        let t = crate::vmc::stream::clock_seconds(micros);
        if let Some(p) = &mut self.protocol {
            p.decode(bytes, &mut |r| self.readings.push((t, r)));
        }
    }

    /// The readings due: by tick marks, those the recorded run had taken `ticks` ticks
    /// after the device opened; by time, those recorded up to `seconds` after the first.
    pub(crate) fn take(&mut self, ticks: u64, seconds: f64) -> Vec<Reading> {
        self.take_timed(ticks, seconds)
            .into_iter()
            .map(|(_, r)| r)
            .collect()
    }

    /// The readings due, as [`StreamFeed::take`], each with its recorded time in seconds.
    pub(crate) fn take_timed(&mut self, ticks: u64, seconds: f64) -> Vec<(f64, Reading)> {
        let end = if self.by_ticks {
            let mut end = self.next;
            while let Some(&(tick, taken)) = self.marks.front() {
                if tick > ticks {
                    break;
                }
                end = end.max(taken as usize);
                self.marks.pop_front();
            }
            if end > self.readings.len() {
                tracing::warn!(
                    "a replayed device took {end} readings where its bytes decode to {}",
                    self.readings.len()
                );
            }
            end.min(self.readings.len())
        } else {
            let t0 = self.readings.first().map(|r| r.0).unwrap_or(0.0);
            let mut end = self.next;
            while end < self.readings.len() && self.readings[end].0 - t0 <= seconds + 1e-9 {
                end += 1;
            }
            end
        };
        let out = self.readings[self.next..end].to_vec();
        self.next = end;
        out
    }

    /// The receiver clock (microseconds) the recorded run read `ticks` ticks after the
    /// device opened: its clock mark's, or the newest before it; `None` without any.
    pub(crate) fn clock_at(&mut self, ticks: u64) -> Option<u64> {
        while let Some(&(tick, micros)) = self.clocks.front() {
            if tick > ticks {
                break;
            }
            self.clock = Some(micros);
            self.clocks.pop_front();
        }
        self.clock
    }

    /// What the stream's decoder could not use in the bytes decoded so far (a file's are
    /// decoded when it is opened): (messages or records, their bytes).
    pub(crate) fn counters(&self) -> (u64, u64) {
        self.protocol.as_ref().map_or((0, 0), |p| p.counters())
    }

    /// The recorded time of the first reading, in seconds.
    pub(crate) fn first_time(&self) -> Option<f64> {
        self.readings.first().map(|r| r.0)
    }
}

/// A shared stream feed (the device's source holds one, the replay fills it).
pub type SharedFeed = Arc<Mutex<StreamFeed>>;

/// Recorded inputs replayed in place of the scene's live and relayed devices and its
/// messages from outside. Installed as Lua app data before the scene loads, so a device
/// with `port`, `zenoh` or a VRPN `device` reads the stream of its name instead.
#[derive(Clone)]
pub struct DeviceReplay(Arc<Mutex<ReplayState>>);

struct ReplayState {
    /// Where the inputs come from, for messages (`--replay-devices run.rec`).
    origin: String,
    /// For a stream arriving in pieces: its chunks so far.
    reader: Option<ChunkReader>,
    /// Feeds by stream index.
    streams: Vec<SharedFeed>,
    /// Feeds by device name (asked for by the scene, or declared by the recording).
    by_name: HashMap<String, SharedFeed>,
    /// Whether every stream goes out by tick marks.
    by_ticks: bool,
    /// Messages from outside not yet delivered.
    messages: VecDeque<RecordedMessage>,
    /// Whether all chunks are known (a file): a device not in it is an error.
    complete: bool,
}

impl DeviceReplay {
    /// The inputs of a `.rec` file (`troupe run --record-devices` writes one).
    pub fn from_file(path: &Path) -> Result<DeviceReplay, RecordError> {
        let rec = Recording::read(path)?;
        let mut by_name = HashMap::new();
        let mut streams = Vec::new();
        for (i, info) in rec.streams.iter().enumerate() {
            // A stream no decoder reads (an unknown kind) is refused only if asked for.
            let feed = StreamFeed::from_recording(&rec, i).unwrap_or_else(|e| StreamFeed {
                error: Some(e.to_string()),
                ..StreamFeed::default()
            });
            let feed = Arc::new(Mutex::new(feed));
            by_name.insert(info.name.clone(), feed.clone());
            streams.push(feed);
        }
        Ok(DeviceReplay(Arc::new(Mutex::new(ReplayState {
            origin: format!("--replay-devices {}", path.display()),
            reader: None,
            streams,
            by_name,
            by_ticks: !rec.marks.is_empty(),
            messages: rec.messages.into(),
            complete: true,
        }))))
    }

    /// Inputs that arrive in pieces ([`DeviceReplay::feed`]), always by tick marks (a
    /// leader's stream).
    pub fn live(origin: &str) -> DeviceReplay {
        DeviceReplay(Arc::new(Mutex::new(ReplayState {
            origin: origin.to_string(),
            reader: Some(ChunkReader::default()),
            streams: Vec::new(),
            by_name: HashMap::new(),
            by_ticks: true,
            messages: VecDeque::new(),
            complete: false,
        })))
    }

    /// Adds `.rec` chunks (no magic; a piece may end inside a chunk).
    pub fn feed(&self, bytes: &[u8]) -> Result<(), String> {
        let mut g = self.0.lock().map_err(|_| "replay lock poisoned")?;
        let origin = g.origin.clone();
        let reader = g
            .reader
            .as_mut()
            .ok_or("a file replay takes no more chunks")?;
        let items = reader.read(bytes).map_err(|e| format!("{origin}: {e}"))?;
        for item in items {
            match item {
                Item::Stream(info) => {
                    let feed = g.by_name.entry(info.name.clone()).or_default().clone();
                    let mut f = feed.lock().map_err(|_| "feed lock poisoned")?;
                    f.by_ticks = true;
                    match protocol_from_settings(&info.kind, &info.settings) {
                        Ok(p) => f.protocol = Some(p),
                        Err(e) => f.error = Some(format!("{} ({}): {e}", info.name, info.kind)),
                    }
                    drop(f);
                    g.streams.push(feed);
                }
                Item::Data(c) => {
                    if let Some(feed) = g.streams.get(usize::from(c.stream)) {
                        let mut f = feed.lock().map_err(|_| "feed lock poisoned")?;
                        f.decode(c.micros, &c.bytes);
                    }
                }
                Item::Mark(m) => {
                    if let Some(feed) = g.streams.get(usize::from(m.stream)) {
                        let mut f = feed.lock().map_err(|_| "feed lock poisoned")?;
                        f.marks.push_back((m.tick, m.taken));
                    }
                }
                Item::Clock(c) => {
                    if let Some(feed) = g.streams.get(usize::from(c.stream)) {
                        let mut f = feed.lock().map_err(|_| "feed lock poisoned")?;
                        f.clocks.push_back((c.tick, c.micros));
                    }
                }
                Item::Message(m) => g.messages.push_back(m),
            }
        }
        Ok(())
    }

    /// The feed of the device named `name` (`pat.glove`), in place of its live source.
    pub(crate) fn stream(&self, name: &str) -> Result<SharedFeed, String> {
        let mut g = self.0.lock().map_err(|_| "replay lock poisoned")?;
        if let Some(feed) = g.by_name.get(name) {
            if let Some(e) = feed.lock().ok().and_then(|f| f.error.clone()) {
                return Err(format!("{}: {e}", g.origin));
            }
            return Ok(feed.clone());
        }
        if g.complete {
            let mut known: Vec<&String> = g.by_name.keys().collect();
            known.sort();
            return Err(format!(
                "{}: no stream named {name} (the recording has {known:?})",
                g.origin
            ));
        }
        // A leader's stream declares it later: the feed waits for its header.
        let by_ticks = g.by_ticks;
        let feed = Arc::new(Mutex::new(StreamFeed {
            by_ticks,
            ..StreamFeed::default()
        }));
        g.by_name.insert(name.to_string(), feed.clone());
        Ok(feed)
    }

    /// Where the inputs come from (`--replay-devices run.rec`).
    pub fn origin(&self) -> String {
        self.0.lock().map(|g| g.origin.clone()).unwrap_or_default()
    }

    /// The input that delivers the recorded messages at their ticks.
    pub fn messages(&self) -> ReplayedMessages {
        ReplayedMessages(self.clone())
    }
}

/// Delivers a replay's messages from outside at the ticks they were recorded (an input).
pub struct ReplayedMessages(DeviceReplay);

impl Input for ReplayedMessages {
    fn name(&self) -> String {
        format!("{} (messages)", self.0.origin())
    }

    fn poll(&mut self, scene: &mut Scene) -> troupe_scene::Result<()> {
        // The coming tick's script phase sees what the recorded one saw, in recorded order.
        let tick = scene.tick() + 1;
        let mut due = Vec::new();
        if let Ok(mut g) = self.0 .0.lock() {
            while g.messages.front().is_some_and(|m| m.tick <= tick) {
                let m = g.messages.pop_front().expect("a front message");
                due.push(Message {
                    key: m.key,
                    value: m.value,
                    remote: true,
                });
            }
        }
        scene.mailbox_mut().deliver_in_order(due);
        Ok(())
    }
}

/// Records the messages from outside that each tick delivered (an observer), beside the
/// device streams of the same recorder.
pub struct RecordMessages(pub Arc<crate::record::writer::Recorder>);

impl troupe_scene::Observer for RecordMessages {
    fn name(&self) -> String {
        "recorded messages".into()
    }

    fn publish(&mut self, scene: &Scene, _: &[troupe_scene::Event]) -> troupe_scene::Result<()> {
        for m in scene.mailbox().delivered().iter().filter(|m| m.remote) {
            self.0.message(scene.tick(), &m.key, &m.value);
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::record::file::MAGIC;
    use crate::record::writer::Recorder;
    use serde_json::json;

    /// A SpaceMouse report pushing the cap right by `x` (one report, one reading).
    fn report(x: i16) -> Vec<u8> {
        let mut r = vec![1u8];
        for axis in [x, 0, 0, 0, 0, 0] {
            r.extend_from_slice(&axis.to_le_bytes());
        }
        r
    }

    /// Three readings; the run took the first at tick 0 and the other two at tick 2; a
    /// message came at tick 1.
    fn chunks() -> Vec<u8> {
        let rec = Recorder::tap_only();
        let s = rec.add_stream("mouse", "spacemouse", json!({}));
        for x in [10, 20, 30] {
            rec.data(s, &report(x));
        }
        rec.mark(s, 0, 1);
        rec.message(1, "cue/a", &json!({"n": 5}));
        rec.mark(s, 2, 3);
        rec.take_tap()
    }

    fn xs(readings: Vec<Reading>) -> Vec<i16> {
        readings
            .into_iter()
            .map(|r| match r {
                Reading::SpaceMouse(s) => s.translation[0],
                other => panic!("{other:?}"),
            })
            .collect()
    }

    #[test]
    fn a_stream_arriving_in_pieces_hands_out_readings_at_the_marked_ticks() {
        let replay = DeviceReplay::live("a leader");
        // Asked for before its header arrives, as a follower's scene loads first.
        let feed = replay.stream("mouse").unwrap();
        for piece in chunks().chunks(5) {
            replay.feed(piece).unwrap();
        }
        let mut f = feed.lock().unwrap();
        assert_eq!(xs(f.take(0, 0.0)).len(), 1);
        assert!(f.take(1, 9.0).is_empty(), "by ticks, not by time");
        let later = xs(f.take(2, 0.0));
        assert_eq!(later.len(), 2);
        assert!(later[0] < later[1]);
        drop(f);
        let mut messages = replay.messages();
        let mut scene = Scene::new(troupe_scene::SceneConfig::default()).unwrap();
        scene.mailbox_mut().begin_tick();
        messages.poll(&mut scene).unwrap();
        let inbox = scene.mailbox_mut().take_inbox();
        assert_eq!(inbox.len(), 1, "the message of tick 1 is due before tick 1");
        assert_eq!(
            (inbox[0].key.as_str(), &inbox[0].value),
            ("cue/a", &json!({"n": 5}))
        );
    }

    #[test]
    fn a_vmc_stream_hands_out_datagrams_with_their_arrival_and_each_ticks_clock() {
        let rec = Recorder::tap_only();
        let s = rec.add_stream("pat.vmc", "vmc", json!({ "zenoh": "stage/vmc" }));
        rec.data_at(s, 1_000, b"one");
        rec.mark(s, 0, 1);
        rec.clock(s, 0, 1_200);
        rec.data_at(s, 9_000, b"two");
        rec.clock(s, 1, 11_200);
        rec.mark(s, 2, 2);
        rec.clock(s, 2, 21_300);
        let replay = DeviceReplay::live("a leader");
        let feed = replay.stream("pat.vmc").unwrap();
        for piece in rec.take_tap().chunks(7) {
            replay.feed(piece).unwrap();
        }
        let datagram = |b: &[u8]| Reading::Datagram { bytes: b.to_vec() };
        let mut f = feed.lock().unwrap();
        let micros = crate::vmc::stream::clock_seconds;
        assert_eq!(f.take_timed(0, 0.0), [(micros(1_000), datagram(b"one"))]);
        assert_eq!(f.clock_at(0), Some(1_200));
        // Tick 1 took nothing though "two" had arrived: by ticks, not by arrival.
        assert!(f.take_timed(1, 5.0).is_empty());
        assert_eq!(f.clock_at(1), Some(11_200));
        assert_eq!(f.take_timed(2, 0.0), [(micros(9_000), datagram(b"two"))]);
        assert_eq!(f.clock_at(2), Some(21_300));
        // A tick without its own clock mark keeps the newest.
        assert_eq!(f.clock_at(7), Some(21_300));
    }

    #[test]
    fn a_file_replay_names_the_streams_it_has_and_refuses_bad_chunks() {
        let dir = std::env::temp_dir().join(format!("troupe-feed-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("run.rec");
        std::fs::write(&path, [MAGIC.as_slice(), &chunks()].concat()).unwrap();
        let replay = DeviceReplay::from_file(&path).unwrap();
        let err = replay.stream("pat.glove").err().unwrap();
        assert!(
            err.contains("no stream named pat.glove") && err.contains("\"mouse\""),
            "{err}"
        );
        let feed = replay.stream("mouse").unwrap();
        assert_eq!(feed.lock().unwrap().take(5, 0.0).len(), 3);
        // A message chunk that is not JSON is refused with its offset.
        let mut bad = vec![b'M'];
        bad.extend_from_slice(&1u64.to_le_bytes());
        bad.extend_from_slice(&3u32.to_le_bytes());
        bad.extend_from_slice(b"{{{");
        let err = DeviceReplay::live("a leader").feed(&bad).unwrap_err();
        assert!(err.contains("message at byte 11"), "{err}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
