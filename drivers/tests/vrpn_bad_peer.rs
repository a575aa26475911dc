//! A VRPN client facing peers that are not good VRPN servers: silent after accepting,
//! another major version, garbage, lengths that lie, a close mid-message. Each ends in an
//! error in the device's health (and a retry), never a panic or a blocked caller.

use std::io::{Read, Write};
use std::net::TcpListener;
use std::time::{Duration, Instant};
use troupe_drivers::device::{DeviceHandle, DriverOptions, HealthReport, HealthState};
use troupe_drivers::vrpn::wire::{encode, name_payload, system, COOKIE};
use troupe_drivers::vrpn::{self, DeviceName, VrpnConfig};

/// A TCP peer on a loopback port that runs `serve` on each connection it accepts, each on
/// its own thread.
fn peer(serve: impl Fn(std::net::TcpStream) + Send + Sync + 'static) -> u16 {
    let l = TcpListener::bind("127.0.0.1:0").unwrap();
    let port = l.local_addr().unwrap().port();
    let serve = std::sync::Arc::new(serve);
    std::thread::spawn(move || {
        for s in l.incoming().flatten() {
            let serve = serve.clone();
            std::thread::spawn(move || serve(s));
        }
    });
    port
}

fn client(port: u16, handshake: Duration, attempts: Option<u32>) -> DeviceHandle {
    let name = format!("Tracker0@tcp://127.0.0.1:{port}");
    let mut o = DriverOptions::new(&name, "");
    o.max_attempts = attempts;
    o.backoff_max = Duration::from_millis(100);
    let cfg = VrpnConfig::new(&DeviceName::parse(&name).unwrap(), &[]);
    vrpn::spawn(cfg, o, handshake, None).unwrap()
}

fn wait_until(h: &DeviceHandle, f: impl Fn(&HealthReport) -> bool) -> HealthReport {
    let start = Instant::now();
    loop {
        let r = h.health.report();
        if f(&r) {
            return r;
        }
        assert!(start.elapsed() < Duration::from_secs(5), "{r:?}");
        std::thread::sleep(Duration::from_millis(10));
    }
}

#[test]
fn a_server_that_never_answers_the_handshake_fails_within_the_timeout() {
    let port = peer(|s| {
        std::thread::sleep(Duration::from_secs(3));
        drop(s);
    });
    let start = Instant::now();
    let h = client(port, Duration::from_millis(300), Some(1));
    let r = wait_until(&h, |r| r.state == HealthState::Failed);
    assert!(
        start.elapsed() < Duration::from_secs(1),
        "{:?}",
        start.elapsed()
    );
    let e = r.last_error.unwrap();
    assert!(
        e.contains("no VRPN cookie within 0.3 s (got 0 of 24 bytes)"),
        "{e}"
    );
}

#[test]
fn a_peer_that_falls_silent_after_the_handshake_is_dropped_and_retried() {
    let port = peer(|mut s| {
        let mut cookie = [0u8; 24];
        if s.read_exact(&mut cookie).is_ok() {
            let _ = s.write_all(COOKIE);
            // Then nothing, not even pongs, with the connection open.
            std::thread::sleep(Duration::from_secs(10));
        }
    });
    let start = Instant::now();
    let h = client(port, Duration::from_secs(1), None);
    let r = wait_until(&h, |r| r.connections >= 2);
    assert!(
        start.elapsed() < Duration::from_secs(5),
        "{:?}",
        start.elapsed()
    );
    let e = r.last_error.unwrap();
    assert!(e.contains("nothing from the server for 3 s"), "{e}");
}

#[test]
fn another_major_version_is_refused_by_name() {
    let port = peer(|mut s| {
        let _ = s.write_all(b"vrpn: ver. 06.01  0\0\0\0\0\0");
        std::thread::sleep(Duration::from_millis(200));
    });
    let h = client(port, Duration::from_secs(1), Some(1));
    let r = wait_until(&h, |r| r.state == HealthState::Failed);
    let e = r.last_error.unwrap();
    assert!(e.contains("major version 6 (06.01)"), "{e}");
}

#[test]
fn garbage_lying_lengths_and_a_close_mid_message_are_errors_and_the_client_retries() {
    // Each connection: a good cookie and descriptions, then one kind of bad input.
    let bad: Vec<Vec<u8>> = vec![
        // A header whose length is shorter than a header.
        [3u32.to_be_bytes(), [0; 4], [0; 4], [0; 4], [0; 4], [0; 4]].concat(),
        // A length past the limit.
        [
            u32::MAX.to_be_bytes(),
            [0; 4],
            [0; 4],
            [0; 4],
            [0; 4],
            [0; 4],
        ]
        .concat(),
        // A report of an undescribed type, then a short report, then a cut message.
        [
            encode(0, 0, 0, 99, &[1, 2, 3]),
            encode(0, 0, 0, 1, &[0, 0, 0, 1]),
            encode(0, 0, 0, 1, &[0; 64])[..40].to_vec(),
        ]
        .concat(),
        // Random bytes.
        (0..500u32)
            .map(|i| (i.wrapping_mul(2654435761) >> 13) as u8)
            .collect(),
    ];
    let port = peer(move |mut s| {
        static N: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
        let i = N.fetch_add(1, std::sync::atomic::Ordering::SeqCst) % 4;
        let mut cookie = [0u8; 24];
        if s.read_exact(&mut cookie).is_err() {
            return;
        }
        let hello = [
            COOKIE.to_vec(),
            encode(
                0,
                0,
                0,
                system::SENDER_DESCRIPTION,
                &name_payload("Tracker0"),
            ),
            encode(
                0,
                0,
                1,
                system::TYPE_DESCRIPTION,
                &name_payload("vrpn_Tracker Pos_Quat"),
            ),
        ]
        .concat();
        let _ = s.write_all(&hello);
        let _ = s.write_all(&bad[i]);
        std::thread::sleep(Duration::from_millis(50));
    });
    let h = client(port, Duration::from_secs(1), None);
    let r = wait_until(&h, |r| r.connections >= 6);
    assert!(
        r.resyncs >= 2,
        "undescribed and short reports are counted: {r:?}"
    );
    assert!(r.last_error.is_some(), "{r:?}");
    // A caller draining the channel is never blocked, and nothing decoded wrongly.
    assert!(h.drain().is_empty());
}

proptest::proptest! {
    /// Any bytes, in any pieces, through the decoder a recording replays with: no panic,
    /// and whatever decodes is a reading of the wanted device.
    #[test]
    fn any_bytes_decode_without_panic(
        chunks in proptest::collection::vec(proptest::collection::vec(proptest::num::u8::ANY, 0..200), 0..8),
        prefix in proptest::bool::ANY,
    ) {
        use troupe_drivers::device::{Protocol, Reading};
        let cfg = VrpnConfig { device: "Tracker0@h".into(), senders: vec!["Tracker0".into()] };
        let mut p = vrpn::VrpnProtocol::new(cfg, Default::default());
        if prefix {
            p.decode(&encode(0, 0, 0, system::SENDER_DESCRIPTION, &name_payload("Tracker0")), &mut |_| {});
            p.decode(&encode(0, 0, 0, system::TYPE_DESCRIPTION, &name_payload("vrpn_Tracker Pos_Quat")), &mut |_| {});
        }
        for c in chunks {
            p.decode(&c, &mut |r| assert!(matches!(&r, Reading::Vrpn(v) if v.device() == "Tracker0")));
        }
        let _ = p.counters();
    }
}
