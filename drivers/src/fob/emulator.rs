//! A Flock of Birds emulator: answers the commands the driver sends and encodes records of
//! its motion exactly as the documented formats say, on a pseudo-terminal.
//!
//! Commands and their argument counts follow `shared/reference/devices.md`, section
//! "Ascension Flock of Birds (RS-232)".

use crate::emulator::options::EmulatorOptions;
use crate::emulator::pty::Pty;
use crate::fob::commands::{self, OutputFormat, ReportRate};
use crate::fob::decoder::{encode_record, RecordLayout};
use crate::fob::pose::pose_words;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

/// The Flock of Birds emulator's state.
pub struct FobEmulator {
    options: EmulatorOptions,
    format: OutputFormat,
    hemisphere: [u8; 2],
    rate: ReportRate,
    group: bool,
    streaming: bool,
    /// Pending command bytes not yet complete.
    pending: Vec<u8>,
    /// Expanded error code (EXAMINE VALUE 0x10).
    error: u8,
    start: Instant,
}

impl FobEmulator {
    /// A flock at power-up: POSITION/ANGLES, forward hemisphere, every cycle, not streaming.
    pub fn new(options: EmulatorOptions) -> FobEmulator {
        FobEmulator {
            options,
            format: OutputFormat::PositionAngles,
            hemisphere: [0, 0],
            rate: ReportRate::Every,
            group: false,
            streaming: false,
            pending: Vec::new(),
            error: 0,
            start: Instant::now(),
        }
    }

    fn layout(&self) -> RecordLayout {
        RecordLayout {
            format: self.format,
            button: false,
            group: self.group,
            range: self.options.range,
        }
    }

    /// One report: every bird's record in group mode, else bird 1's.
    pub fn report(&self, t: f64) -> Vec<u8> {
        let layout = self.layout();
        let birds = if self.group {
            self.options.birds.max(1)
        } else {
            1
        };
        let mut out = Vec::new();
        for i in 0..birds {
            let (p, q) = self.options.motion.bird(t, usize::from(i));
            let words = pose_words(self.format, self.options.range, p, q);
            out.extend(encode_record(&layout, &words, 0, i + 1));
        }
        out
    }

    /// Consumes command bytes; returns the reply bytes. Incomplete commands wait for more.
    pub fn handle(&mut self, bytes: &[u8], t: f64) -> Vec<u8> {
        self.pending.extend_from_slice(bytes);
        let mut reply = Vec::new();
        loop {
            let p = &self.pending;
            let Some(&c) = p.first() else { break };
            // The RS232-TO-FBB prefix addresses the next command to one bird; the emulator
            // keeps one format for the whole flock, so the prefix is consumed with it.
            let (addr_len, cmd) = if (0xF1..=0xFE).contains(&c) {
                match p.get(1) {
                    Some(&c2) => (1, c2),
                    None => break,
                }
            } else {
                (0, c)
            };
            let extra = match cmd {
                commands::CMD_HEMISPHERE => 2,
                commands::CMD_EXAMINE => 1,
                commands::CMD_CHANGE => 2,
                _ => 0,
            };
            let need = addr_len + 1 + extra;
            if p.len() < need {
                break;
            }
            let args: Vec<u8> = p[addr_len + 1..need].to_vec();
            self.pending.drain(..need);
            match cmd {
                commands::CMD_POINT => {
                    self.streaming = false;
                    reply.extend(self.report(t));
                }
                commands::CMD_STREAM => self.streaming = true,
                commands::CMD_RUN => {}
                commands::CMD_SLEEP => self.streaming = false,
                commands::CMD_FBB_RESET => self.group = false,
                commands::CMD_HEMISPHERE => self.hemisphere = [args[0], args[1]],
                commands::CMD_EXAMINE => match args[0] {
                    commands::PARAM_FBB_STATUS => {
                        let s = commands::STATUS_ACCESSIBLE
                            | commands::STATUS_RUNNING
                            | commands::STATUS_RECEIVER;
                        reply.extend(std::iter::repeat_n(s, usize::from(self.options.birds)));
                    }
                    commands::PARAM_ERROR_CODE => reply.extend([self.error, 0]),
                    commands::PARAM_GROUP_MODE => reply.push(u8::from(self.group)),
                    _ => reply.extend([0, 0]),
                },
                commands::CMD_CHANGE => match args[0] {
                    commands::PARAM_GROUP_MODE => self.group = args[1] != 0,
                    commands::PARAM_AUTO_CONFIG => {
                        if args[1] != self.options.birds {
                            // The FBB has as many units as it has; a wrong count is an error.
                            self.error = 0x0E;
                        }
                    }
                    _ => self.error = 0x0D,
                },
                other => {
                    if let Some(f) = OutputFormat::from_command(other) {
                        self.format = f;
                    } else if let Some(r) = ReportRate::from_command(other) {
                        self.rate = r;
                    } else {
                        self.error = 0x0C;
                    }
                }
            }
        }
        reply
    }

    /// Serves the pty until stopped.
    pub fn run(mut self, pty: &Pty, stop: &AtomicBool) {
        let mut buf = [0u8; 256];
        let mut next = Instant::now();
        while !stop.load(Ordering::Acquire) {
            let n = match pty.read_timeout(&mut buf, Duration::from_millis(2)) {
                Ok(n) => n,
                Err(_) => {
                    std::thread::sleep(Duration::from_millis(5));
                    0
                }
            };
            let t = self.start.elapsed().as_secs_f64();
            if n > 0 {
                let reply = self.handle(&buf[..n], t);
                if !reply.is_empty() && pty.write_all(&reply).is_err() {
                    continue;
                }
            }
            if self.streaming && Instant::now() >= next {
                let period = f64::from(self.rate.divisor()) / self.options.rate_hz.max(1.0);
                next += Duration::from_secs_f64(period);
                if next < Instant::now() {
                    next = Instant::now();
                }
                let _ = pty.write_all(&self.report(t));
            }
        }
    }
}
