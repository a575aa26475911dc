//! A published scene on the loopback interface, with explicit endpoints and no scouting:
//! a leader and two subscribers in their own Zenoh sessions.

use std::net::TcpListener;
use std::time::{Duration, Instant};
use troupe_net::subscriber::actor_bodies;
use troupe_net::{Endpoints, PoseFeed, PoseMessage, SceneKeys, ScenePublisher};
use troupe_scene::{ActorDesc, Scene, SceneConfig, Session};
use zenoh::Wait;

/// A TCP port nobody listens on now.
fn free_port() -> u16 {
    TcpListener::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port()
}

fn scene() -> Scene {
    let mut scene = Scene::new(SceneConfig::default()).unwrap();
    scene.add_actor(&ActorDesc::new("ann")).unwrap();
    scene.add_actor(&ActorDesc::new("bob")).unwrap();
    scene
}

/// Puts a probe on a pose key until every feed has seen it, so the leader knows of the
/// subscribers before the run starts (interest travels asynchronously after connecting).
fn await_routes(leader: &zenoh::Session, keys: &SceneKeys, feeds: &[&PoseFeed]) {
    let probe = keys.pose("probe").unwrap();
    let deadline = Instant::now() + Duration::from_secs(10);
    let mut seen = vec![false; feeds.len()];
    while !seen.iter().all(|s| *s) {
        assert!(
            Instant::now() < deadline,
            "subscribers never saw the leader"
        );
        leader.put(&probe, b"probe".to_vec()).wait().unwrap();
        std::thread::sleep(Duration::from_millis(20));
        for (s, feed) in seen.iter_mut().zip(feeds) {
            while let Ok(m) = feed.received().try_recv() {
                *s |= m.actor == "probe";
            }
        }
    }
}

#[test]
fn a_leader_with_two_subscribers_publishes_every_posture_bit_for_bit() {
    let port = free_port();
    let leader_session = Endpoints::loopback_listener(port).open().unwrap();
    let subscriber = || Endpoints::loopback_peer(port).open().unwrap();
    let (one, two) = (subscriber(), subscriber());
    let keys = SceneKeys::new("troupe/test-two-subscribers").unwrap();
    let feeds = [
        PoseFeed::subscribe(&one, &keys).unwrap(),
        PoseFeed::subscribe(&two, &keys).unwrap(),
    ];
    await_routes(&leader_session, &keys, &[&feeds[0], &feeds[1]]);

    let mut session = Session::new(scene());
    let publisher = ScenePublisher::new(leader_session.clone(), keys.clone()).unwrap();
    let handle = session.observe(publisher);
    // The DOF names are served before the first tick.
    session.start().unwrap();
    let mut expected: Vec<(String, u64, Vec<f64>)> = Vec::new();
    let remember = |session: &Session, expected: &mut Vec<(String, u64, Vec<f64>)>| {
        for (a, s) in session
            .scene()
            .actors()
            .iter()
            .zip(session.scene().states())
        {
            expected.push((a.name.clone(), session.scene().tick(), s.q.clone()));
        }
    };
    remember(&session, &mut expected);
    let ticks = 200;
    for t in 0..ticks {
        // Something moves: one DOF of each actor follows the tick.
        let v = (t as f64 * 0.01).sin();
        session.scene_mut().set_dofs(0, &[(7, v)]).unwrap();
        session.scene_mut().set_dofs(1, &[(8, -v)]).unwrap();
        session.tick().unwrap();
        remember(&session, &mut expected);
        // A little slower than the network, as a paced run is.
        std::thread::sleep(Duration::from_millis(1));
    }
    assert_eq!(session.observer(handle).dropped_ticks(), 0);
    let bodies = actor_bodies(&one, &keys, Duration::from_secs(5)).unwrap();
    let skeleton = &session.scene().actors()[0].skeleton;
    let want: Vec<String> = skeleton.dofs().iter().map(|d| d.name.clone()).collect();
    let names: Vec<(String, Vec<String>)> = bodies.into_iter().map(|b| (b.actor, b.dofs)).collect();
    assert_eq!(
        names,
        vec![("ann".into(), want.clone()), ("bob".into(), want)]
    );
    let line = session.finish().unwrap();
    assert_eq!(
        line,
        vec![format!(
            "published {} ticks on zenoh under {}",
            ticks + 1,
            keys.prefix()
        )]
    );

    for (i, feed) in feeds.iter().enumerate() {
        let deadline = Instant::now() + Duration::from_secs(10);
        let mut got: Vec<PoseMessage> = Vec::new();
        while got.len() < expected.len() && Instant::now() < deadline {
            if let Ok(m) = feed.received().recv_timeout(Duration::from_millis(100)) {
                got.push(m);
            }
        }
        let mut got: Vec<(String, u64, Vec<u64>)> = got
            .into_iter()
            .map(|m| {
                let p = m.posture.expect("a well-formed packet");
                (
                    m.actor,
                    p.tick,
                    p.values.iter().map(|v| v.to_bits()).collect(),
                )
            })
            .collect();
        got.sort();
        let mut want: Vec<(String, u64, Vec<u64>)> = expected
            .iter()
            .map(|(a, t, q)| (a.clone(), *t, q.iter().map(|v| v.to_bits()).collect()))
            .collect();
        want.sort();
        assert_eq!(got.len(), want.len(), "subscriber {i} missed postures");
        assert!(got == want, "subscriber {i} got other postures");
    }
}

#[test]
fn a_subscriber_that_goes_away_does_not_stop_the_leader() {
    let port = free_port();
    let leader = Endpoints::loopback_listener(port).open().unwrap();
    let follower = Endpoints::loopback_peer(port).open().unwrap();
    let keys = SceneKeys::new("troupe/test-vanish").unwrap();
    let feed = PoseFeed::subscribe(&follower, &keys).unwrap();
    await_routes(&leader, &keys, &[&feed]);
    let mut session = Session::new(scene());
    let handle = session.observe(ScenePublisher::new(leader, keys).unwrap());
    for t in 0..100 {
        if t == 50 {
            follower.close().wait().unwrap();
        }
        session.tick().unwrap();
    }
    // Every tick ran; each was queued or, when the network thread was behind (ticks here
    // are not paced), dropped whole and counted: nothing waited for the gone subscriber.
    assert_eq!(session.scene().tick(), 100);
    let publisher = session.observer(handle);
    assert_eq!(publisher.published_ticks() + publisher.dropped_ticks(), 101);
    let lines = session.finish().unwrap();
    assert!(lines[0].starts_with("published "), "{lines:?}");
}

#[test]
fn a_name_that_cannot_be_a_key_is_refused_by_name() {
    let session = Endpoints::loopback_listener(0).open().unwrap();
    let keys = SceneKeys::new("troupe/test-bad-name").unwrap();
    let mut scene = Scene::new(SceneConfig::default()).unwrap();
    scene.add_actor(&ActorDesc::new("two words")).unwrap();
    let mut run = Session::new(scene);
    run.observe(ScenePublisher::new(session, keys).unwrap());
    let err = run.start().unwrap_err().to_string();
    assert!(err.contains("two words"), "{err}");
}
