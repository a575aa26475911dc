//! The devices' side of the Lua API: one call installs `troupe.performer`,
//! `troupe.devices.*` and `troupe.devices.spacemouse` on a session, with the inputs that
//! feed their devices into each tick.

pub(crate) mod args;
pub(crate) mod health;

use crate::performer::registry::SharedPerformers;
use crate::record::writer::Recorder;
use crate::space_move::mover::SharedSpaceMice;
use std::sync::Arc;
use troupe_lua::LuaSession;

/// The Lua functions of the devices could not be installed.
#[derive(Debug, thiserror::Error)]
pub enum InstallError {
    /// `troupe.performer` or `troupe.devices.*`.
    #[error("installing the device functions: {0}")]
    Performers(#[source] mlua::Error),
    /// `troupe.devices.spacemouse`.
    #[error("installing troupe.devices.spacemouse: {0}")]
    SpaceMouse(#[source] mlua::Error),
    /// `troupe.vmc_out`.
    #[error("installing troupe.vmc_out: {0}")]
    Vmc(#[source] mlua::Error),
}

/// What a session's devices share with the program that runs it.
pub struct Devices {
    /// Every performer, their devices and latency measurements.
    pub performers: SharedPerformers,
    /// Every SpaceMouse mover.
    pub space_mice: SharedSpaceMice,
}

/// Installs the device functions on the session's director and the device inputs on the
/// session. `recorder` records every live device stream (`--record-devices`).
pub fn install(
    session: &mut LuaSession,
    recorder: Option<Arc<Recorder>>,
) -> Result<Devices, InstallError> {
    let performers = crate::performer::lua::install(session, recorder.clone())
        .map_err(InstallError::Performers)?;
    // SpaceMice move objects rather than actors; installed after `troupe.devices` exists.
    let space_mice =
        crate::space_move::lua::install(session, recorder).map_err(InstallError::SpaceMouse)?;
    crate::vmc::lua::install(session).map_err(InstallError::Vmc)?;
    Ok(Devices {
        performers,
        space_mice,
    })
}
