//! Devices plugged into another machine and served there by a relay (`troupe relay`):
//! a performer's device table names them with `zenoh = KEY` in place of `port`. The
//! driver thread is the local one (decoder, health, reconnection, `.rec` recording); only
//! its port is opened through [`RemotePorts`], which the command line installs in the
//! Lua state when it has a network session (the drivers know no network).

use crate::device::error::DeviceError;
use crate::device::port::Port;
use std::sync::Arc;

/// Opens the port of a device served under a key (a Zenoh key expression).
pub type RemoteOpen = dyn Fn(&str) -> Result<Box<dyn Port>, DeviceError> + Send + Sync;

/// How `zenoh = KEY` devices are opened: installed as Lua app data by the command line.
#[derive(Clone)]
pub struct RemotePorts(pub Arc<RemoteOpen>);

impl RemotePorts {
    /// The opener the command line installed in `lua`, for the device option `what`
    /// naming `zenoh = key`; without a network session, an error saying how to get one.
    pub(crate) fn from_lua(lua: &mlua::Lua, what: &str, key: &str) -> mlua::Result<RemotePorts> {
        lua.app_data_ref::<RemotePorts>()
            .map(|p| p.clone())
            .ok_or_else(|| {
                troupe_lua::args::err(
                    what,
                    format!(
                        "zenoh = \"{key}\" needs a network session: troupe run with \
                         --zenoh-connect or --zenoh-listen (a troupe built with the zenoh feature)"
                    ),
                )
            })
    }
}
