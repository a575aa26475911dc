//! Replaying a recording: each stream is decoded by the protocol its recorded kind and
//! settings rebuild, so replay runs the very decoder a live device runs.

use crate::cyberglove::protocol::{GloveConfig, GloveProtocol};
use crate::device::protocol::Protocol;
use crate::device::reading::Reading;
use crate::fob::protocol::{FobConfig, FobProtocol};
use crate::record::error::{KindError, RecordError};
use crate::record::file::Recording;
use crate::spacemouse::protocol::SpaceMouseProtocol;
use crate::vmc::stream::{VmcDatagrams, REC_KIND as VMC};
use crate::vrpn::{VrpnConfig, VrpnProtocol};

impl Recording {
    /// A decoder for a stream, built from its recorded settings.
    pub fn protocol(&self, stream: usize) -> Result<Box<dyn Protocol>, RecordError> {
        let info = self
            .streams
            .get(stream)
            .ok_or(RecordError::NoStream(stream))?;
        protocol_from_settings(&info.kind, &info.settings).map_err(|source| RecordError::Stream {
            name: info.name.clone(),
            kind: info.kind.clone(),
            source,
        })
    }

    /// Every reading of a stream with its recorded time in seconds, decoded by the same
    /// decoder a live device uses.
    pub fn readings(&self, stream: usize) -> Result<Vec<(f64, Reading)>, RecordError> {
        let mut p = self.protocol(stream)?;
        let mut out = Vec::new();
        for c in self
            .chunks
            .iter()
            .filter(|c| usize::from(c.stream) == stream)
        {
            let t = c.micros as f64 * 1e-6;
            p.decode(&c.bytes, &mut |r| out.push((t, r)));
        }
        Ok(out)
    }
}

/// Rebuilds a protocol from the settings a driver recorded.
pub fn protocol_from_settings(
    kind: &str,
    settings: &serde_json::Value,
) -> Result<Box<dyn Protocol>, KindError> {
    match kind {
        "fob" => {
            let c: FobConfig = serde_json::from_value(settings.clone())?;
            Ok(Box::new(FobProtocol::new(c)))
        }
        "cyberglove" => {
            let c: GloveConfig = serde_json::from_value(settings.clone())?;
            Ok(Box::new(GloveProtocol::new(c)))
        }
        "spacemouse" => Ok(Box::new(SpaceMouseProtocol::default())),
        VMC => Ok(Box::new(VmcDatagrams)),
        "vrpn" => {
            let c: VrpnConfig = serde_json::from_value(settings.clone())?;
            Ok(Box::new(VrpnProtocol::new(c, Default::default())))
        }
        other => Err(KindError::Unknown(other.to_string())),
    }
}
