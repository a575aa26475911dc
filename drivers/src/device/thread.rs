//! The device thread: one per device, timestamped samples over a bounded channel, a health
//! state with counters, and reconnection with backoff.
//!
//! The tick loop only ever calls `try_recv` on the channel, so a slow or silent device never
//! blocks it; a device thread that finds the channel full drops the sample and counts it.

use crate::device::error::DeviceError;
use crate::device::health::{Health, HealthState};
use crate::device::port::{open_serial, Port};
use crate::device::protocol::Protocol;
use crate::device::reading::Sample;
use crate::record::writer::Recorder;
use crossbeam::channel::{bounded, Receiver, Sender, TrySendError};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

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
    /// The recorder and this device's stream in it, when recording.
    recording: Option<(Arc<Recorder>, u16)>,
}

impl DeviceHandle {
    /// All samples waiting, without blocking.
    pub fn drain(&self) -> Vec<Sample> {
        self.samples.try_iter().collect()
    }

    /// All samples waiting, noting in the recording (if any) that `ticks` ticks after the
    /// device opened the scene had taken them, so a replay takes them at the same tick.
    pub fn drain_at_tick(&self, ticks: u64) -> Vec<Sample> {
        let samples = self.drain();
        if let (Some((recorder, stream)), Some(last)) = (&self.recording, samples.last()) {
            recorder.mark(*stream, ticks, last.seq + 1);
        }
        samples
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
pub type Opener = Box<dyn FnMut(&DriverOptions) -> Result<Box<dyn Port>, DeviceError> + Send>;

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
    // Declared here, before the thread starts, so the handle knows its stream for marks.
    let recording = recorder.map(|r| {
        let stream = r.add_stream(&options.name, protocol.kind(), protocol.settings());
        (r, stream)
    });
    let thread_recording = recording.clone();
    let thread = std::thread::Builder::new()
        .name(format!("device {}", options.name))
        .spawn(move || run(options, protocol, thread_recording, opener, tx, h, s))
        .ok();
    if thread.is_none() {
        health.set_state(HealthState::Failed);
        health.set_error("could not start the device thread".into());
    }
    DeviceHandle {
        samples: rx,
        health,
        stop,
        thread,
        recording,
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
    recording: Option<(Arc<Recorder>, u16)>,
    mut opener: Opener,
    tx: Sender<Sample>,
    health: Arc<Health>,
    stop: Arc<AtomicBool>,
) {
    let start = Instant::now();
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
                health.set_error(e.to_string());
                if o.max_attempts.is_some_and(|m| failures >= m) {
                    health.set_state(HealthState::Failed);
                    return;
                }
                health.set_state(HealthState::Reconnecting);
                sleep_unless_stopped(backoff, &stop);
                backoff = (backoff * 2).min(o.backoff_max);
                continue;
            }
        };
        failures = 0;
        backoff = o.backoff_initial;
        health.connections.fetch_add(1, Ordering::Relaxed);
        health.set_state(HealthState::Connected);
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
                    if let Some((r, s)) = &recording {
                        r.data(*s, &buf[..n]);
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
                        health.set_state(HealthState::Streaming);
                    }
                }
                Err(e)
                    if e.kind() == std::io::ErrorKind::TimedOut
                        || e.kind() == std::io::ErrorKind::WouldBlock => {}
                Err(e) => break format!("read: {e}"),
            }
            let silent_since = last_sample.unwrap_or(connected_at);
            if silent_since.elapsed() > o.stale_after {
                health.set_state(HealthState::Stale);
            }
        };
        let (r, d) = protocol.counters();
        base_resyncs += r;
        base_dropped += d;
        tracing::debug!(device = %o.name, "disconnected: {reason}");
        health.set_error(reason);
        health.set_state(HealthState::Reconnecting);
        drop(port);
        sleep_unless_stopped(backoff, &stop);
    }
}
