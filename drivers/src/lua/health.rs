//! A device's health as the Lua table `troupe.devices.health` answers with.

use crate::device::health::HealthReport;
use mlua::{Lua, Table};

/// A device's health as a Lua table (`troupe.devices.health`): its state and counters, or
/// `state = "replay"` for a replayed device or a glove fed over OSC (`None`).
pub fn health_table(lua: &Lua, report: Option<HealthReport>) -> mlua::Result<Table> {
    let t = lua.create_table()?;
    match report {
        Some(h) => {
            t.set("state", h.state.name())?;
            t.set("samples", h.samples)?;
            t.set("resyncs", h.resyncs)?;
            t.set("dropped_bytes", h.dropped_bytes)?;
            t.set("dropped_samples", h.dropped_samples)?;
            t.set("connections", h.connections)?;
            t.set("error", h.last_error)?;
        }
        None => t.set("state", "replay")?,
    }
    Ok(t)
}
