//! A device's health: its connection state and counters, shared between its thread and
//! whoever reports on it.

use serde::Serialize;
use std::sync::atomic::{AtomicU64, AtomicU8, Ordering};

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
    /// Zero counters, `reconnecting`: where a device thread starts before its first
    /// connection.
    pub(crate) fn new() -> Health {
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
        h.set_state(state);
        h
    }

    /// Sets the state.
    pub fn set_state(&self, s: HealthState) {
        self.state.store(s as u8, Ordering::Release);
    }

    /// Records the last error.
    pub fn set_error(&self, e: String) {
        if let Ok(mut g) = self.last_error.lock() {
            *g = Some(e);
        }
    }

    /// Current state.
    pub fn state(&self) -> HealthState {
        HealthState::from_u8(self.state.load(Ordering::Acquire))
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
