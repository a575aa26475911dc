//! The driver framework: one thread per device, timestamped samples over a bounded
//! channel, a health state with counters, and reconnection with backoff.
//!
//! The tick loop only ever calls `try_recv` on the channel, so a slow or silent device never
//! blocks it; a device thread that finds the channel full drops the sample and counts it.

use crate::fob::{self, BirdRecord, RecordDecoder, RecordLayout};
use crate::glove::{self, GloveDecoder, GloveLayout, GloveRecord, Query};
use crate::record::Recorder;
use crossbeam::channel::{bounded, Receiver, Sender, TrySendError};
use serde::{Deserialize, Serialize};
use std::io::{Read, Write};
use std::sync::atomic::{AtomicBool, AtomicU64, AtomicU8, Ordering};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// What a device produced.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(tag = "kind", rename_all = "lowercase")]
pub enum Reading {
    /// One Flock of Birds record (one bird).
    Bird(BirdRecord),
    /// One CyberGlove record.
    Glove(GloveRecord),
    /// The state of a SpaceMouse after one HID report.
    #[serde(rename = "spacemouse")]
    SpaceMouse(crate::spacemouse::SpaceMouseState),
}

/// A timestamped reading.
#[derive(Clone, Debug)]
pub struct Sample {
    /// Per-device sequence number, from 0.
    pub seq: u64,
    /// When the bytes that completed the sample were read.
    pub arrived: Instant,
    /// Seconds since the driver started (or, on replay, the recorded time).
    pub time: f64,
    /// The decoded reading.
    pub reading: Reading,
}

/// Health of a device.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum HealthState {
    /// Port open and configured, no sample yet.
    Connected,
    /// Samples arriving.
    Streaming,
    /// Connected, but no sample for longer than the stale time.
    Stale,
    /// The port is closed; trying again with backoff.
    Reconnecting,
    /// Gave up after the configured number of attempts.
    Failed,
}

impl HealthState {
    fn from_u8(v: u8) -> HealthState {
        match v {
            0 => HealthState::Connected,
            1 => HealthState::Streaming,
            2 => HealthState::Stale,
            3 => HealthState::Reconnecting,
            _ => HealthState::Failed,
        }
    }

    /// The lower-case name.
    pub fn name(self) -> &'static str {
        match self {
            HealthState::Connected => "connected",
            HealthState::Streaming => "streaming",
            HealthState::Stale => "stale",
            HealthState::Reconnecting => "reconnecting",
            HealthState::Failed => "failed",
        }
    }
}

/// Shared health state and counters, updated by the device thread.
#[derive(Debug)]
pub struct Health {
    state: AtomicU8,
    /// Samples decoded.
    pub samples: AtomicU64,
    /// Framing losses.
    pub resyncs: AtomicU64,
    /// Bytes dropped while resynchronizing.
    pub dropped_bytes: AtomicU64,
    /// Samples dropped because the channel was full.
    pub dropped_samples: AtomicU64,
    /// Successful (re)connections.
    pub connections: AtomicU64,
    /// Last error text (open or configure failure, read error).
    last_error: std::sync::Mutex<Option<String>>,
}

/// A copy of the health at one moment.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct HealthReport {
    /// Current state.
    pub state: HealthState,
    /// Samples decoded.
    pub samples: u64,
    /// Framing losses.
    pub resyncs: u64,
    /// Bytes dropped while resynchronizing.
    pub dropped_bytes: u64,
    /// Samples dropped because the channel was full.
    pub dropped_samples: u64,
    /// Successful (re)connections.
    pub connections: u64,
    /// Last error, if any.
    pub last_error: Option<String>,
}

impl Health {
    fn new() -> Health {
        Health {
            state: AtomicU8::new(3),
            samples: AtomicU64::new(0),
            resyncs: AtomicU64::new(0),
            dropped_bytes: AtomicU64::new(0),
            dropped_samples: AtomicU64::new(0),
            connections: AtomicU64::new(0),
            last_error: std::sync::Mutex::new(None),
        }
    }

    /// A fresh health record in the given state (for sources other than serial drivers).
    pub fn new_state(state: HealthState) -> Health {
        let h = Health::new();
        h.set(state);
        h
    }

    /// Sets the state.
    pub fn set_state(&self, s: HealthState) {
        self.set(s);
    }

    /// Records the last error.
    pub fn set_error(&self, e: String) {
        self.error(e);
    }

    /// Current state.
    pub fn state(&self) -> HealthState {
        HealthState::from_u8(self.state.load(Ordering::Acquire))
    }

    fn set(&self, s: HealthState) {
        self.state.store(s as u8, Ordering::Release);
    }

    fn error(&self, e: String) {
        if let Ok(mut g) = self.last_error.lock() {
            *g = Some(e);
        }
    }

    /// A snapshot of state and counters.
    pub fn report(&self) -> HealthReport {
        HealthReport {
            state: self.state(),
            samples: self.samples.load(Ordering::Relaxed),
            resyncs: self.resyncs.load(Ordering::Relaxed),
            dropped_bytes: self.dropped_bytes.load(Ordering::Relaxed),
            dropped_samples: self.dropped_samples.load(Ordering::Relaxed),
            connections: self.connections.load(Ordering::Relaxed),
            last_error: self.last_error.lock().ok().and_then(|g| g.clone()),
        }
    }
}

/// A byte stream to a device (a serial port, or anything readable and writable with a
/// read timeout).
pub trait Port: Read + Write + Send {}
impl<T: Read + Write + Send + ?Sized> Port for T {}

/// Opens a serial port at a baud rate, 8N1, with a short read timeout so the thread can
/// notice a stop request and a silent device.
pub fn open_serial(path: &str, baud: u32) -> Result<Box<dyn Port>, String> {
    let port = serialport::new(path, baud)
        .timeout(Duration::from_millis(20))
        .data_bits(serialport::DataBits::Eight)
        .parity(serialport::Parity::None)
        .stop_bits(serialport::StopBits::One)
        .flow_control(serialport::FlowControl::None)
        .open()
        .map_err(|e| format!("opening serial port {path}: {e}"))?;
    Ok(Box::new(port))
}

/// A device protocol: configures the device after each connection and decodes its bytes.
pub trait Protocol: Send {
    /// Short device kind (`fob`, `cyberglove`), used in recordings.
    fn kind(&self) -> &'static str;
    /// Settings needed to decode a recording of this device, as JSON.
    fn settings(&self) -> serde_json::Value;
    /// Sends the configuration and starts the data flow; fails with a message naming what
    /// the device answered wrongly.
    fn configure(&mut self, port: &mut dyn Port) -> Result<(), String>;
    /// Called before each read: a polled device sends its poll command here.
    fn before_read(&mut self, _port: &mut dyn Port) -> std::io::Result<()> {
        Ok(())
    }
    /// Decodes bytes into readings.
    fn decode(&mut self, bytes: &[u8], out: &mut dyn FnMut(Reading));
    /// (resyncs, dropped bytes) so far.
    fn counters(&self) -> (u64, u64);
    /// Stops the data flow before the port closes.
    fn stop(&mut self, _port: &mut dyn Port) {}
}

/// POINT (one record per request) or STREAM (continuous).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Mode {
    /// The driver asks for each record.
    Point,
    /// The device sends records continuously.
    Stream,
}

/// Flock of Birds configuration.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FobConfig {
    /// Number of birds (1 = standalone; more = group mode over the FBB).
    pub birds: u8,
    /// Record layout (format, button, range; `group` is set from `birds`).
    pub layout: RecordLayout,
    /// Hemisphere.
    pub hemisphere: fob::Hemisphere,
    /// Report rate.
    pub rate: fob::ReportRate,
    /// POINT or STREAM.
    pub mode: Mode,
}

impl FobConfig {
    /// A flock of `birds` in the given format, forward hemisphere, every cycle, streaming.
    pub fn new(birds: u8, format: fob::OutputFormat) -> FobConfig {
        let mut layout = RecordLayout::single(format);
        layout.group = birds > 1;
        FobConfig {
            birds,
            layout,
            hemisphere: fob::Hemisphere::Forward,
            rate: fob::ReportRate::Every,
            mode: Mode::Stream,
        }
    }
}

/// The Flock of Birds protocol.
pub struct FobProtocol {
    config: FobConfig,
    decoder: RecordDecoder,
    /// POINT mode: whether the next request may be sent (the last one was answered).
    poll_due: bool,
    /// POINT mode: when the last request was sent.
    last_poll: Instant,
    /// POINT mode: records still expected for the last request (one per bird).
    awaited: usize,
}

impl FobProtocol {
    /// A protocol for the given configuration.
    pub fn new(config: FobConfig) -> FobProtocol {
        let decoder = RecordDecoder::new(config.layout, 1);
        FobProtocol {
            config,
            decoder,
            poll_due: true,
            last_poll: Instant::now(),
            awaited: 0,
        }
    }
}

fn write_all(port: &mut dyn Port, bytes: &[u8]) -> Result<(), String> {
    port.write_all(bytes)
        .and_then(|_| port.flush())
        .map_err(|e| format!("writing {bytes:02x?}: {e}"))
}

/// Reads exactly `n` bytes or fails after `timeout`.
fn read_exact_timeout(port: &mut dyn Port, n: usize, timeout: Duration) -> Result<Vec<u8>, String> {
    let start = Instant::now();
    let mut out = Vec::with_capacity(n);
    let mut buf = [0u8; 64];
    while out.len() < n {
        if start.elapsed() > timeout {
            return Err(format!("timed out after {} of {n} reply bytes", out.len()));
        }
        let want = (n - out.len()).min(buf.len());
        match port.read(&mut buf[..want]) {
            Ok(0) => return Err("port closed".into()),
            Ok(k) => out.extend_from_slice(&buf[..k]),
            Err(e)
                if e.kind() == std::io::ErrorKind::TimedOut
                    || e.kind() == std::io::ErrorKind::WouldBlock => {}
            Err(e) => return Err(e.to_string()),
        }
    }
    Ok(out)
}

/// Reads and discards whatever arrives within `quiet` (stale records of an earlier stream).
fn drain(port: &mut dyn Port, quiet: Duration) {
    let start = Instant::now();
    let mut buf = [0u8; 256];
    while start.elapsed() < quiet {
        match port.read(&mut buf) {
            Ok(0) => break,
            Ok(_) => {}
            Err(e)
                if e.kind() == std::io::ErrorKind::TimedOut
                    || e.kind() == std::io::ErrorKind::WouldBlock => {}
            Err(_) => break,
        }
    }
}

impl Protocol for FobProtocol {
    fn kind(&self) -> &'static str {
        "fob"
    }

    fn settings(&self) -> serde_json::Value {
        serde_json::to_value(&self.config).unwrap_or(serde_json::Value::Null)
    }

    fn configure(&mut self, port: &mut dyn Port) -> Result<(), String> {
        let c = &self.config;
        // Stop an earlier stream (POINT ends STREAM mode) and throw away what is in flight.
        write_all(port, &[fob::CMD_SLEEP])?;
        write_all(port, &[fob::CMD_RUN])?;
        drain(port, Duration::from_millis(60));
        if c.birds > 1 {
            // FBB AUTO-CONFIG with the number of units, then check every unit answers with a
            // receiver (reference: EXAMINE VALUE 0x24 returns per-unit status, 0x80
            // accessible, 0x40 running, 0x20 has a receiver).
            write_all(port, &fob::auto_config_command(c.birds))?;
            write_all(port, &[fob::CMD_EXAMINE, fob::PARAM_FBB_STATUS])?;
            let status = read_exact_timeout(port, usize::from(c.birds), Duration::from_millis(500))
                .map_err(|e| format!("flock status (EXAMINE VALUE 0x24): {e}"))?;
            for (i, s) in status.iter().enumerate() {
                if s & fob::STATUS_ACCESSIBLE == 0 || s & fob::STATUS_RECEIVER == 0 {
                    return Err(format!(
                        "bird {} reports status 0x{s:02x}: not accessible or no receiver",
                        i + 1
                    ));
                }
            }
            // Format and hemisphere go to each bird through the RS232-TO-FBB prefix.
            for addr in 1..=c.birds {
                write_all(port, &[fob::CMD_TO_FBB + addr, c.layout.format.command()])?;
                let h = c.hemisphere.data();
                write_all(
                    port,
                    &[fob::CMD_TO_FBB + addr, fob::CMD_HEMISPHERE, h[0], h[1]],
                )?;
            }
            write_all(port, &fob::group_mode_command(true))?;
        } else {
            // A flock left in group mode by an earlier session would label every bird's
            // records as this one's.
            write_all(port, &fob::group_mode_command(false))?;
            write_all(port, &[c.layout.format.command()])?;
            let h = c.hemisphere.data();
            write_all(port, &[fob::CMD_HEMISPHERE, h[0], h[1]])?;
        }
        write_all(port, &[c.rate.command()])?;
        if c.mode == Mode::Stream {
            write_all(port, &[fob::CMD_STREAM])?;
        }
        // A fresh decoder per connection: the thread adds its counters to the earlier totals.
        self.decoder = RecordDecoder::new(c.layout, 1);
        self.poll_due = true;
        Ok(())
    }

    fn before_read(&mut self, port: &mut dyn Port) -> std::io::Result<()> {
        // One POINT request per answered report (a record from every bird in group mode):
        // a request on every read would pile replies up in the port. A lost reply must
        // not stall polling forever: re-poll after 100 ms.
        if self.config.mode == Mode::Point
            && (self.poll_due || self.last_poll.elapsed() > Duration::from_millis(100))
        {
            port.write_all(&[fob::CMD_POINT])?;
            self.poll_due = false;
            self.awaited = usize::from(self.config.birds.max(1));
            self.last_poll = Instant::now();
        }
        Ok(())
    }

    fn decode(&mut self, bytes: &[u8], out: &mut dyn FnMut(Reading)) {
        let mut records = 0;
        self.decoder.feed(bytes, |r| {
            records += 1;
            out(Reading::Bird(r))
        });
        if records > 0 {
            self.awaited = self.awaited.saturating_sub(records);
            if self.awaited == 0 {
                self.poll_due = true;
            }
        }
    }

    fn counters(&self) -> (u64, u64) {
        let s = self.decoder.stats();
        (s.resyncs, s.dropped_bytes)
    }

    fn stop(&mut self, port: &mut dyn Port) {
        let _ = write_all(port, &[fob::CMD_POINT]);
    }
}

/// CyberGlove configuration.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct GloveConfig {
    /// Record layout; `sensors` is checked against the glove's answer to `?S`.
    pub layout: GloveLayout,
    /// `G` poll or `S` stream.
    pub mode: Mode,
}

/// The CyberGlove protocol.
pub struct GloveProtocol {
    config: GloveConfig,
    decoder: GloveDecoder,
    /// Whether the driver must send a `G` (POINT mode: one outstanding poll at a time).
    poll_due: bool,
    last_poll: Instant,
}

impl GloveProtocol {
    /// A protocol for the given configuration.
    pub fn new(config: GloveConfig) -> GloveProtocol {
        GloveProtocol {
            decoder: GloveDecoder::new(config.layout),
            config,
            poll_due: true,
            last_poll: Instant::now(),
        }
    }
}

/// Sends a query and reads its reply.
pub fn glove_query(port: &mut dyn Port, q: Query) -> Result<Vec<u8>, String> {
    write_all(port, &q.command())?;
    let start = Instant::now();
    let mut buf = Vec::new();
    let mut chunk = [0u8; 64];
    loop {
        match glove::parse_query_reply(q, &buf) {
            Ok(Some((reply, _))) => return Ok(reply.payload),
            Ok(None) => {}
            Err(e) => return Err(format!("query ?{}: {e}", q.letter() as char)),
        }
        if start.elapsed() > Duration::from_millis(500) {
            return Err(format!(
                "query ?{}: no complete reply within 500 ms (got {buf:02x?})",
                q.letter() as char
            ));
        }
        match port.read(&mut chunk) {
            Ok(0) => return Err("port closed".into()),
            Ok(k) => buf.extend_from_slice(&chunk[..k]),
            Err(e)
                if e.kind() == std::io::ErrorKind::TimedOut
                    || e.kind() == std::io::ErrorKind::WouldBlock => {}
            Err(e) => return Err(e.to_string()),
        }
    }
}

impl Protocol for GloveProtocol {
    fn kind(&self) -> &'static str {
        "cyberglove"
    }

    fn settings(&self) -> serde_json::Value {
        serde_json::to_value(&self.config).unwrap_or(serde_json::Value::Null)
    }

    fn configure(&mut self, port: &mut dyn Port) -> Result<(), String> {
        // Stop a stream left running by an earlier session, then ask what is there.
        write_all(port, &[glove::CMD_STOP])?;
        drain(port, Duration::from_millis(60));
        let status = glove_query(port, Query::Status)?;
        // `?G` status: bit0 initialized, bit1 glove plugged in.
        if status.first().is_none_or(|s| s & 0x02 == 0) {
            return Err(format!(
                "glove not plugged into its interface unit (status {status:02x?})"
            ));
        }
        let sensors = glove_query(port, Query::SensorsSampled)?;
        let n = usize::from(sensors.first().copied().unwrap_or(0));
        if n != self.config.layout.sensors {
            return Err(format!(
                "the glove samples {n} sensors, configured for {}",
                self.config.layout.sensors
            ));
        }
        // `u 1` / `u 0`: status byte appended or not (ASCII command, CR-terminated).
        let u: &[u8] = if self.config.layout.status_byte {
            b"u 1\r"
        } else {
            b"u 0\r"
        };
        write_all(port, u)?;
        drain(port, Duration::from_millis(30));
        self.decoder = GloveDecoder::new(self.config.layout);
        self.poll_due = true;
        if self.config.mode == Mode::Stream {
            write_all(port, &[glove::CMD_STREAM])?;
        }
        Ok(())
    }

    fn before_read(&mut self, port: &mut dyn Port) -> std::io::Result<()> {
        // A lost reply must not stall polling forever: re-poll after 100 ms.
        if self.config.mode == Mode::Point
            && (self.poll_due || self.last_poll.elapsed() > Duration::from_millis(100))
        {
            port.write_all(&[glove::CMD_POLL])?;
            self.poll_due = false;
            self.last_poll = Instant::now();
        }
        Ok(())
    }

    fn decode(&mut self, bytes: &[u8], out: &mut dyn FnMut(Reading)) {
        let mut got = false;
        self.decoder.feed(bytes, |r| {
            got = true;
            out(Reading::Glove(r))
        });
        if got {
            self.poll_due = true;
        }
    }

    fn counters(&self) -> (u64, u64) {
        let s = self.decoder.stats();
        (s.resyncs, s.dropped_bytes)
    }

    fn stop(&mut self, port: &mut dyn Port) {
        let _ = write_all(port, &[glove::CMD_STOP]);
    }
}

/// How a driver thread connects and watches its device.
#[derive(Clone, Debug)]
pub struct DriverOptions {
    /// Device name (for logs and recordings).
    pub name: String,
    /// Serial port path.
    pub path: String,
    /// Baud rate.
    pub baud: u32,
    /// A connected device silent this long is `stale`.
    pub stale_after: Duration,
    /// First reconnection delay; doubles up to `backoff_max`.
    pub backoff_initial: Duration,
    /// Longest reconnection delay.
    pub backoff_max: Duration,
    /// Give up (`failed`) after this many failed attempts in a row; `None` = never.
    pub max_attempts: Option<u32>,
    /// Channel capacity in samples.
    pub capacity: usize,
}

impl DriverOptions {
    /// Defaults: 115200 baud, stale after 250 ms, backoff 50 ms … 2 s, never give up,
    /// 1024 samples of buffer.
    pub fn new(name: &str, path: &str) -> DriverOptions {
        DriverOptions {
            name: name.to_string(),
            path: path.to_string(),
            baud: 115_200,
            stale_after: Duration::from_millis(250),
            backoff_initial: Duration::from_millis(50),
            backoff_max: Duration::from_secs(2),
            max_attempts: None,
            capacity: 1024,
        }
    }
}

/// A running device: its samples, its health, and the thread (stopped on drop).
pub struct DeviceHandle {
    /// Samples, oldest first.
    pub samples: Receiver<Sample>,
    /// Health and counters.
    pub health: Arc<Health>,
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<()>>,
}

impl DeviceHandle {
    /// All samples waiting, without blocking.
    pub fn drain(&self) -> Vec<Sample> {
        self.samples.try_iter().collect()
    }

    /// Stops the thread and waits for it.
    pub fn stop(mut self) {
        self.shutdown();
    }

    fn shutdown(&mut self) {
        self.stop.store(true, Ordering::Release);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

impl Drop for DeviceHandle {
    fn drop(&mut self) {
        self.shutdown();
    }
}

/// Opens ports for a driver: the serial port by default; tests can substitute another.
pub type Opener = Box<dyn FnMut(&DriverOptions) -> Result<Box<dyn Port>, String> + Send>;

/// Starts a device thread on a serial port.
pub fn spawn(
    options: DriverOptions,
    protocol: Box<dyn Protocol>,
    recorder: Option<Arc<Recorder>>,
) -> DeviceHandle {
    let opener: Opener = Box::new(|o: &DriverOptions| open_serial(&o.path, o.baud));
    spawn_with(options, protocol, recorder, opener)
}

/// Starts a device thread with a given way to open its port.
pub fn spawn_with(
    options: DriverOptions,
    protocol: Box<dyn Protocol>,
    recorder: Option<Arc<Recorder>>,
    opener: Opener,
) -> DeviceHandle {
    let (tx, rx) = bounded(options.capacity.max(1));
    let health = Arc::new(Health::new());
    let stop = Arc::new(AtomicBool::new(false));
    let (h, s) = (health.clone(), stop.clone());
    let thread = std::thread::Builder::new()
        .name(format!("device {}", options.name))
        .spawn(move || run(options, protocol, recorder, opener, tx, h, s))
        .ok();
    if thread.is_none() {
        health.set(HealthState::Failed);
        health.error("could not start the device thread".into());
    }
    DeviceHandle {
        samples: rx,
        health,
        stop,
        thread,
    }
}

/// Sleeps up to `d`, in small steps, returning early when asked to stop.
fn sleep_unless_stopped(d: Duration, stop: &AtomicBool) {
    let end = Instant::now() + d;
    while !stop.load(Ordering::Acquire) {
        let now = Instant::now();
        if now >= end {
            break;
        }
        std::thread::sleep((end - now).min(Duration::from_millis(10)));
    }
}

fn run(
    o: DriverOptions,
    mut protocol: Box<dyn Protocol>,
    recorder: Option<Arc<Recorder>>,
    mut opener: Opener,
    tx: Sender<Sample>,
    health: Arc<Health>,
    stop: Arc<AtomicBool>,
) {
    let start = Instant::now();
    let stream = recorder
        .as_ref()
        .map(|r| r.add_stream(&o.name, protocol.kind(), protocol.settings()));
    let mut seq = 0u64;
    let mut failures = 0u32;
    let mut backoff = o.backoff_initial;
    // Counters of earlier connections, so totals survive a reconnection.
    let (mut base_resyncs, mut base_dropped) = (0u64, 0u64);
    while !stop.load(Ordering::Acquire) {
        let connected =
            opener(&o).and_then(|mut port| protocol.configure(port.as_mut()).map(|_| port));
        let mut port = match connected {
            Ok(p) => p,
            Err(e) => {
                failures += 1;
                tracing::debug!(device = %o.name, "connect attempt {failures} failed: {e}");
                health.error(e);
                if o.max_attempts.is_some_and(|m| failures >= m) {
                    health.set(HealthState::Failed);
                    return;
                }
                health.set(HealthState::Reconnecting);
                sleep_unless_stopped(backoff, &stop);
                backoff = (backoff * 2).min(o.backoff_max);
                continue;
            }
        };
        failures = 0;
        backoff = o.backoff_initial;
        health.connections.fetch_add(1, Ordering::Relaxed);
        health.set(HealthState::Connected);
        let mut last_sample: Option<Instant> = None;
        let connected_at = Instant::now();
        let mut buf = [0u8; 512];
        let reason = loop {
            if stop.load(Ordering::Acquire) {
                protocol.stop(port.as_mut());
                return;
            }
            if let Err(e) = protocol.before_read(port.as_mut()) {
                break format!("write: {e}");
            }
            match port.read(&mut buf) {
                Ok(0) => break "port closed".to_string(),
                Ok(n) => {
                    let now = Instant::now();
                    if let (Some(r), Some(s)) = (&recorder, stream) {
                        r.data(s, &buf[..n]);
                    }
                    let mut produced = false;
                    protocol.decode(&buf[..n], &mut |reading| {
                        produced = true;
                        let sample = Sample {
                            seq,
                            arrived: now,
                            time: now.duration_since(start).as_secs_f64(),
                            reading,
                        };
                        seq += 1;
                        health.samples.fetch_add(1, Ordering::Relaxed);
                        if let Err(TrySendError::Full(_)) = tx.try_send(sample) {
                            health.dropped_samples.fetch_add(1, Ordering::Relaxed);
                        }
                    });
                    let (r, d) = protocol.counters();
                    health.resyncs.store(base_resyncs + r, Ordering::Relaxed);
                    health
                        .dropped_bytes
                        .store(base_dropped + d, Ordering::Relaxed);
                    if produced {
                        last_sample = Some(now);
                        health.set(HealthState::Streaming);
                    }
                }
                Err(e)
                    if e.kind() == std::io::ErrorKind::TimedOut
                        || e.kind() == std::io::ErrorKind::WouldBlock => {}
                Err(e) => break format!("read: {e}"),
            }
            let silent_since = last_sample.unwrap_or(connected_at);
            if silent_since.elapsed() > o.stale_after {
                health.set(HealthState::Stale);
            }
        };
        let (r, d) = protocol.counters();
        base_resyncs += r;
        base_dropped += d;
        tracing::debug!(device = %o.name, "disconnected: {reason}");
        health.error(reason);
        health.set(HealthState::Reconnecting);
        drop(port);
        sleep_unless_stopped(backoff, &stop);
    }
}
