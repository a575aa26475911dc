//! `troupe relay KIND --port PATH --key KEY --zenoh-…`: serves a serial device on Zenoh
//! from the machine it is plugged into; a performer on the simulation host names it with
//! `zenoh = KEY` (docs/distributed.md, "Remote device hosts").

use anyhow::{bail, Context, Result};
use clap::Args;
use std::process::ExitCode;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};
use troupe_net::relay::{serve, RelayStats};
use troupe_net::Endpoints;

/// Options of `troupe relay`.
#[derive(Args)]
pub struct RelayArgs {
    /// The device kind: fob or cyberglove (devices on a serial port).
    pub kind: String,
    /// The serial port the device is on.
    #[arg(long)]
    pub port: String,
    /// Baud rate.
    #[arg(long, default_value_t = 115_200)]
    pub baud: u32,
    /// The key the device is served under (a performer names it with `zenoh = KEY`).
    #[arg(long)]
    pub key: String,
    /// A Zenoh endpoint to connect to, e.g. tcp/10.0.0.5:7447 (repeatable).
    #[arg(long, value_name = "ENDPOINT")]
    pub zenoh_connect: Vec<String>,
    /// A Zenoh endpoint to listen on, e.g. tcp/0.0.0.0:7448 (repeatable).
    #[arg(long, value_name = "ENDPOINT")]
    pub zenoh_listen: Vec<String>,
    /// Stop after this many seconds (default: run until killed).
    #[arg(long)]
    pub seconds: Option<f64>,
}

/// Serves the device until the time is up, reopening its port when it fails.
pub fn run(args: RelayArgs) -> Result<ExitCode> {
    if !matches!(args.kind.as_str(), "fob" | "cyberglove") {
        bail!(
            "troupe relay {}: relays serve serial devices (fob, cyberglove); VRPN and OSC \
             sources are on the network already",
            args.kind
        );
    }
    troupe_net::SceneKeys::new(&args.key).context("--key")?;
    let session = Endpoints {
        connect: args.zenoh_connect.clone(),
        listen: args.zenoh_listen.clone(),
    }
    .open()?;
    let stop = Arc::new(AtomicBool::new(false));
    if let Some(s) = args.seconds {
        let stop = stop.clone();
        std::thread::spawn(move || {
            std::thread::sleep(Duration::from_secs_f64(s.max(0.0)));
            stop.store(true, Ordering::Release);
        });
    }
    println!("relaying {} {} on {}", args.kind, args.port, args.key);
    let started = Instant::now();
    let mut total = RelayStats::default();
    while !stop.load(Ordering::Acquire) {
        let served = troupe_drivers::device::open_serial(&args.port, args.baud)
            .map_err(anyhow::Error::new)
            .and_then(|mut port| Ok(serve(&session, &args.key, &mut port, &stop)?));
        match served {
            Ok(stats) => add(&mut total, stats),
            Err(e) => {
                tracing::warn!("relay {}: {e:#}; retrying", args.key);
                std::thread::sleep(Duration::from_millis(500));
            }
        }
    }
    println!(
        "relayed {} chunks ({} bytes) and {} commands in {:.1} s",
        total.chunks,
        total.bytes,
        total.commands,
        started.elapsed().as_secs_f64()
    );
    Ok(ExitCode::SUCCESS)
}

fn add(total: &mut RelayStats, s: RelayStats) {
    total.chunks += s.chunks;
    total.bytes += s.bytes;
    total.commands += s.commands;
}
