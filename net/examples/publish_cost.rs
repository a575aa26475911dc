//! Measures publishing a crowd on Zenoh (docs/PERFORMANCE.md): the tick cost of the
//! publish phase with 1,000 actors, whether anyone listens and when a subscriber is
//! killed mid-run; the payload bandwidth per actor and second; and the delay from a
//! tick's publication to a subscriber on the same machine.
//!
//! `cargo run --release -p troupe-net --example publish_cost [-- ACTORS SECONDS]`
//!
//! Ticks are paced at 100 Hz, as a live installation runs; the figures are per tick.

use std::net::TcpListener;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};
use troupe_net::relay::now_micros;
use troupe_net::zenoh::Wait;
use troupe_net::{Endpoints, SceneKeys, ScenePublisher};
use troupe_scene::{ActorDesc, Scene, SceneConfig, Session};

fn free_port() -> u16 {
    TcpListener::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port()
}

fn crowd(actors: usize) -> Scene {
    let mut scene = Scene::new(SceneConfig::default()).unwrap();
    for i in 0..actors {
        scene.add_actor(&ActorDesc::new(format!("a{i}"))).unwrap();
    }
    scene
}

fn percentile(v: &mut [f64], q: f64) -> f64 {
    v.sort_by(f64::total_cmp);
    v[((v.len() - 1) as f64 * q).round() as usize]
}

/// Runs `seconds` of paced ticks; returns the publish-phase time of each tick (ms).
fn run(session: &mut Session, seconds: f64, mut at_half: impl FnMut()) -> Vec<f64> {
    let ticks = (seconds * 100.0) as u64;
    let period = Duration::from_millis(10);
    let mut next = Instant::now();
    let mut times = Vec::new();
    session.set_phase_timing(true);
    for t in 0..ticks {
        if t == ticks / 2 {
            at_half();
        }
        session.tick().unwrap();
        let p = session.take_phase_times();
        times.push(p.publish.as_secs_f64() * 1e3);
        next += period;
        if let Some(wait) = next.checked_duration_since(Instant::now()) {
            std::thread::sleep(wait);
        }
    }
    times
}

fn report(what: &str, times: &mut [f64]) {
    let mean = times.iter().sum::<f64>() / times.len() as f64;
    println!(
        "{what}: publish phase mean {mean:.3} ms, median {:.3} ms, p99 {:.3} ms per tick",
        percentile(times, 0.5),
        percentile(times, 0.99)
    );
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let actors: usize = args.get(1).and_then(|a| a.parse().ok()).unwrap_or(1000);
    let seconds: f64 = args.get(2).and_then(|a| a.parse().ok()).unwrap_or(5.0);
    let keys = SceneKeys::new("troupe/bench").unwrap();

    // Without a publisher: the baseline publish phase (nothing observes).
    let mut plain = Session::new(crowd(actors));
    let mut times = run(&mut plain, seconds.min(2.0), || {});
    report(&format!("{actors} actors, no publisher"), &mut times);

    // Publishing, nobody listening.
    let port = free_port();
    let leader = Endpoints::loopback_listener(port).open().unwrap();
    let mut alone = Session::new(crowd(actors));
    let handle = alone.observe(ScenePublisher::new(leader.clone(), keys.clone()).unwrap());
    let mut times = run(&mut alone, seconds, || {});
    report(
        &format!("{actors} actors, publishing, no subscriber"),
        &mut times,
    );
    println!(
        "  dropped ticks: {}",
        alone.observer(handle).dropped_ticks()
    );
    alone.finish().unwrap();

    // Publishing to a subscriber that is killed half way through.
    let sub = Endpoints::loopback_peer(port).open().unwrap();
    let bytes = Arc::new(AtomicU64::new(0));
    let packets = Arc::new(AtomicU64::new(0));
    let delays = Arc::new(Mutex::new(Vec::new()));
    let started = Arc::new(Mutex::new(std::collections::HashMap::<u64, u64>::new()));
    let (b, p, d, s) = (
        bytes.clone(),
        packets.clone(),
        delays.clone(),
        started.clone(),
    );
    let subscriber = sub
        .declare_subscriber(keys.all_poses())
        .callback(move |sample| {
            let payload = sample.payload().to_bytes();
            b.fetch_add(payload.len() as u64, Ordering::Relaxed);
            p.fetch_add(1, Ordering::Relaxed);
            if let Ok(posture) = troupe_net::posture::decode(&payload) {
                if let Some(t0) = s.lock().unwrap().get(&posture.tick) {
                    d.lock().unwrap().push((now_micros() - t0) as f64 / 1e3);
                }
            }
        })
        .wait()
        .unwrap();
    std::thread::sleep(Duration::from_secs(1));
    let mut listened = Session::new(crowd(actors));
    // The wall clock of each tick's publication, for the delay to the subscriber.
    listened.observe(Stamp(started.clone()));
    let handle = listened.observe(ScenePublisher::new(leader.clone(), keys.clone()).unwrap());
    let received_at_half = Arc::new(AtomicU64::new(0));
    let r = received_at_half.clone();
    let bytes_half = bytes.clone();
    let t0 = Instant::now();
    let mut sub_holder = Some((sub, subscriber));
    let mut times = run(&mut listened, seconds, || {
        r.store(bytes_half.load(Ordering::Relaxed), Ordering::Relaxed);
        let (sub, subscriber) = sub_holder.take().unwrap();
        drop(subscriber);
        sub.close().wait().unwrap();
    });
    let half = t0.elapsed().as_secs_f64() / 2.0;
    let (first, second): (Vec<f64>, Vec<f64>) = {
        let n = times.len() / 2;
        (times[..n].to_vec(), times[n..].to_vec())
    };
    report(
        &format!("{actors} actors, publishing to a subscriber (whole run)"),
        &mut times,
    );
    report("  first half, subscriber alive", &mut first.clone());
    report("  second half, subscriber killed", &mut second.clone());
    println!(
        "  dropped ticks: {}",
        listened.observer(handle).dropped_ticks()
    );
    let got = received_at_half.load(Ordering::Relaxed) as f64;
    println!(
        "  subscriber received {:.0} KiB of postures in {half:.1} s: {:.1} KiB/s per actor ({} packets)",
        got / 1024.0,
        got / 1024.0 / half / actors as f64,
        packets.load(Ordering::Relaxed)
    );
    let mut d = delays.lock().unwrap().clone();
    if !d.is_empty() {
        println!(
            "  publication-to-subscriber delay: median {:.2} ms, p99 {:.2} ms ({} postures)",
            percentile(&mut d, 0.5),
            percentile(&mut d, 0.99),
            d.len()
        );
    }
    listened.finish().unwrap();
}

/// Notes the wall clock at which each tick was handed to the publisher.
struct Stamp(Arc<Mutex<std::collections::HashMap<u64, u64>>>);
impl troupe_scene::Observer for Stamp {
    fn name(&self) -> String {
        "stamp".into()
    }
    fn publish(&mut self, scene: &Scene, _: &[troupe_scene::Event]) -> troupe_scene::Result<()> {
        self.0.lock().unwrap().insert(scene.tick(), now_micros());
        Ok(())
    }
}
