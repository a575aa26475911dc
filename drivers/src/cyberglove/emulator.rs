//! A CyberGlove emulator: answers polls, streams, queries and the `u` command, and sends
//! records of its motion, on a pseudo-terminal.
//!
//! Commands and replies follow `shared/reference/devices.md`, section "CyberGlove".

use crate::cyberglove::decoder::{self, CMD_QUERY, CMD_STOP};
use crate::emulator::options::EmulatorOptions;
use crate::emulator::pty::Pty;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

/// The CyberGlove emulator's state.
pub struct GloveEmulator {
    options: EmulatorOptions,
    status_byte: bool,
    streaming: bool,
    pending: Vec<u8>,
    start: Instant,
}

impl GloveEmulator {
    /// A glove at power-up: not streaming, no status byte.
    pub fn new(options: EmulatorOptions) -> GloveEmulator {
        GloveEmulator {
            options,
            status_byte: false,
            streaming: false,
            pending: Vec::new(),
            start: Instant::now(),
        }
    }

    /// One record answering `letter`.
    pub fn record(&self, letter: u8, t: f64) -> Vec<u8> {
        let mut v = vec![letter];
        v.extend(self.options.motion.glove(t, self.options.sensors));
        if self.status_byte {
            // Status: initialized and glove plugged in (bits 0 and 1).
            v.push(0x03);
        }
        v.push(0);
        v
    }

    /// Consumes command bytes; returns the reply bytes.
    pub fn handle(&mut self, bytes: &[u8], t: f64) -> Vec<u8> {
        self.pending.extend_from_slice(bytes);
        let mut reply = Vec::new();
        while let Some(&c) = self.pending.first() {
            match c {
                decoder::CMD_POLL => {
                    self.pending.remove(0);
                    reply.extend(self.record(b'G', t));
                }
                decoder::CMD_STREAM => {
                    self.pending.remove(0);
                    self.streaming = true;
                }
                CMD_STOP => {
                    self.pending.remove(0);
                    self.streaming = false;
                }
                CMD_QUERY => {
                    let Some(&q) = self.pending.get(1) else { break };
                    self.pending.drain(..2);
                    let n = self.options.sensors as u8;
                    let payload: Vec<u8> = match q {
                        b'G' => vec![0x03],
                        b'S' | b'N' => vec![n],
                        b'M' => {
                            let mask: u32 = (1u32 << n) - 1;
                            vec![mask as u8, (mask >> 8) as u8, (mask >> 16) as u8]
                        }
                        b'R' => vec![1],
                        b'B' => vec![1],
                        b'T' => vec![0, 10],
                        b'V' => b"troupe-emulator 1".to_vec(),
                        _ => {
                            reply.extend(b"e?");
                            continue;
                        }
                    };
                    reply.extend([b'?', q]);
                    reply.extend(payload);
                    reply.push(0);
                }
                b'a'..=b'z' => {
                    // ASCII command, CR-terminated.
                    let Some(end) = self.pending.iter().position(|&b| b == b'\r') else {
                        break;
                    };
                    let line: Vec<u8> = self.pending.drain(..=end).collect();
                    let text = String::from_utf8_lossy(&line[..line.len() - 1]).to_string();
                    let words: Vec<&str> = text.split_whitespace().collect();
                    match words.as_slice() {
                        ["u", v] => self.status_byte = *v == "1",
                        _ => reply.extend(b"e?"),
                    }
                }
                _ => {
                    self.pending.remove(0);
                    reply.extend(b"e?");
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
            let n = pty
                .read_timeout(&mut buf, Duration::from_millis(2))
                .unwrap_or(0);
            let t = self.start.elapsed().as_secs_f64();
            if n > 0 {
                let reply = self.handle(&buf[..n], t);
                if !reply.is_empty() {
                    let _ = pty.write_all(&reply);
                }
            }
            if self.streaming && Instant::now() >= next {
                next += Duration::from_secs_f64(1.0 / self.options.rate_hz.max(1.0));
                if next < Instant::now() {
                    next = Instant::now();
                }
                let _ = pty.write_all(&self.record(b'S', t));
            }
        }
    }
}
