//! Messages from the network: the scene's `troupe.subscribe` key expressions, subscribed
//! on Zenoh, delivered into the scene's mailbox at the start of the next tick.
//!
//! Only messages from other processes are taken (the scene delivers its own without the
//! network, at the next tick, whether or not it is published). What arrived during a tick
//! is delivered together, sorted by key then text ([`troupe_scene::Mailbox::deliver`]).

use crate::error::NetError;
use crossbeam::channel::{unbounded, Receiver, Sender};
use troupe_scene::{Input, Message, Scene};
use zenoh::pubsub::Subscriber;
use zenoh::sample::Locality;
use zenoh::{Session, Wait};

/// The network side of `troupe.subscribe`: an [`Input`] on a Zenoh session.
pub struct MessageInput {
    session: Session,
    subscribed: Vec<(String, Subscriber<()>)>,
    arrived: Receiver<(String, Vec<u8>)>,
    sender: Sender<(String, Vec<u8>)>,
}

impl MessageInput {
    /// An input that subscribes, on `session`, to what the scene subscribes to.
    pub fn new(session: Session) -> MessageInput {
        let (sender, arrived) = unbounded();
        MessageInput {
            session,
            subscribed: Vec::new(),
            arrived,
            sender,
        }
    }

    /// Declares a Zenoh subscriber for every subscription the scene made since last time.
    fn follow_subscriptions(&mut self, scene: &Scene) -> Result<(), NetError> {
        for expr in scene.mailbox().subscriptions() {
            if self.subscribed.iter().any(|(e, _)| e == expr) {
                continue;
            }
            let tx = self.sender.clone();
            let subscriber = self
                .session
                .declare_subscriber(expr.clone())
                .allowed_origin(Locality::Remote)
                .callback(move |sample| {
                    let key = sample.key_expr().as_str().to_string();
                    let _ = tx.send((key, sample.payload().to_bytes().into_owned()));
                })
                .wait()
                .map_err(|e| NetError::Declare {
                    what: "subscriber",
                    key: expr.clone(),
                    message: e.to_string(),
                })?;
            self.subscribed.push((expr.clone(), subscriber));
        }
        Ok(())
    }
}

impl Input for MessageInput {
    fn name(&self) -> String {
        "zenoh messages".into()
    }

    fn poll(&mut self, scene: &mut Scene) -> troupe_scene::Result<()> {
        let subscribed = self.follow_subscriptions(scene);
        let mut messages = Vec::new();
        let mut refused = Vec::new();
        for (key, bytes) in self.arrived.try_iter() {
            match serde_json::from_slice(&bytes) {
                Ok(value) => messages.push(Message {
                    key,
                    value,
                    remote: true,
                }),
                Err(e) => refused.push(format!("{key}: not JSON ({e})")),
            }
        }
        scene.mailbox_mut().deliver(messages);
        subscribed.map_err(|e| troupe_scene::Error::Invalid(e.to_string()))?;
        match refused.first() {
            Some(first) => Err(troupe_scene::Error::Invalid(format!(
                "{} message(s) refused; first: {first}",
                refused.len()
            ))),
            None => Ok(()),
        }
    }
}
