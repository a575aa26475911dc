//! A troupe built without the `zenoh` feature: the Zenoh options and commands are still
//! parsed, so that using one says plainly what is missing and how to build it, instead of
//! clap's "unexpected argument" (docs/distributed.md, "Build cost").

use anyhow::{bail, Result};
use clap::Args;
use std::process::ExitCode;
use std::sync::Arc;
use troupe_drivers::record::Recorder;
use troupe_lua::LuaSession;
use troupe_scene::SceneConfig;

/// The error for `what` in a build without the feature.
fn not_built(what: &str) -> anyhow::Error {
    anyhow::anyhow!(
        "{what}: this troupe was built without Zenoh (the `zenoh` cargo feature); \
         build it with `cargo build --features zenoh` (docs/distributed.md)"
    )
}

/// `troupe run`'s Zenoh options, refused.
#[derive(Args, Clone, Debug, Default)]
pub struct ZenohArgs {
    /// Needs the zenoh feature.
    #[arg(long, hide = true)]
    zenoh: bool,
    /// Needs the zenoh feature.
    #[arg(long, hide = true, value_name = "ENDPOINT")]
    zenoh_connect: Vec<String>,
    /// Needs the zenoh feature.
    #[arg(long, hide = true, value_name = "ENDPOINT")]
    zenoh_listen: Vec<String>,
    /// Needs the zenoh feature.
    #[arg(long, hide = true, value_name = "KEY")]
    zenoh_prefix: Option<String>,
    /// Needs the zenoh feature.
    #[arg(long, hide = true)]
    zenoh_await_followers: bool,
    /// Needs the zenoh feature.
    #[arg(long, hide = true, value_name = "PREFIX")]
    zenoh_follow: Option<String>,
}

/// Nothing to attach: no network in this build.
pub struct Zenoh;

impl ZenohArgs {
    /// Refuses any Zenoh option.
    pub fn open(&self, config: SceneConfig) -> Result<(SceneConfig, Zenoh)> {
        let flag = [
            (self.zenoh, "--zenoh"),
            (!self.zenoh_connect.is_empty(), "--zenoh-connect"),
            (!self.zenoh_listen.is_empty(), "--zenoh-listen"),
            (self.zenoh_prefix.is_some(), "--zenoh-prefix"),
            (self.zenoh_await_followers, "--zenoh-await-followers"),
            (self.zenoh_follow.is_some(), "--zenoh-follow"),
        ]
        .into_iter()
        .find_map(|(given, flag)| given.then_some(flag));
        match flag {
            Some(flag) => Err(not_built(flag)),
            None => Ok((config, Zenoh)),
        }
    }
}

impl Zenoh {
    /// Never: nothing is published.
    pub fn replicates(&self) -> bool {
        false
    }

    /// Nothing to install.
    pub fn install(&self, _: &LuaSession) {}

    /// Nothing to attach.
    pub fn attach(self, _: &mut LuaSession, _: Option<Arc<Recorder>>) {}
}

/// `troupe view`'s render-node options, refused.
#[derive(Args, Clone, Debug, Default)]
pub struct RemoteViewArgs {
    /// Needs the zenoh feature.
    #[arg(long, hide = true, value_name = "PREFIX")]
    pub zenoh: Option<String>,
    /// Needs the zenoh feature.
    #[arg(long = "zenoh-connect", hide = true, value_name = "ENDPOINT")]
    pub connect: Vec<String>,
}

/// `troupe view --zenoh`, refused.
pub fn run<T>(_: &T, _: &str) -> Result<ExitCode> {
    Err(not_built("troupe view --zenoh"))
}

/// `troupe relay`'s arguments, whatever they are.
#[derive(Args, Clone, Debug)]
pub struct RelayArgs {
    /// Needs the zenoh feature.
    #[arg(trailing_var_arg = true, allow_hyphen_values = true, hide = true)]
    rest: Vec<String>,
}

/// `troupe relay`, refused.
pub fn relay(_: RelayArgs) -> Result<ExitCode> {
    bail!(not_built("troupe relay"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_zenoh_option_names_the_feature_and_how_to_build_it() {
        let args = ZenohArgs {
            zenoh_connect: vec!["tcp/127.0.0.1:7447".into()],
            ..ZenohArgs::default()
        };
        let err = args.open(SceneConfig::default()).err().unwrap().to_string();
        assert!(
            err.starts_with("--zenoh-connect: this troupe was built without Zenoh")
                && err.contains("`cargo build --features zenoh`"),
            "{err}"
        );
        assert!(ZenohArgs::default().open(SceneConfig::default()).is_ok());
        let err = relay(RelayArgs { rest: vec![] }).unwrap_err().to_string();
        assert!(
            err.starts_with("troupe relay: this troupe was built without Zenoh"),
            "{err}"
        );
    }
}
