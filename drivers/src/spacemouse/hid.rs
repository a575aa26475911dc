//! SpaceMice through hidapi: listing HID devices (SpaceMouse family marked), reading a
//! SpaceMouse directly, and opening one as a device-thread port.

use crate::device::error::DeviceError;
use crate::device::port::Port;
use crate::spacemouse::decoder::{self as spacemouse, ReportKind, SpaceMouseState};
use serde::Serialize;
use std::time::{Duration, Instant};

/// A HID device found on the system.
#[derive(Clone, Debug, Serialize)]
pub struct HidInfo {
    /// hidraw path.
    pub path: String,
    /// Vendor ID.
    pub vendor: u16,
    /// Product ID.
    pub product: u16,
    /// Product string the device reports.
    pub name: String,
    /// The SpaceMouse model, when it is one.
    pub spacemouse: Option<String>,
}

/// HID devices (hidraw); an error when HID access is unavailable.
pub fn hid_devices() -> Result<Vec<HidInfo>, DeviceError> {
    let api = hidapi::HidApi::new()?;
    Ok(api
        .device_list()
        .map(|d| HidInfo {
            path: d.path().to_string_lossy().into_owned(),
            vendor: d.vendor_id(),
            product: d.product_id(),
            name: d.product_string().unwrap_or("").to_string(),
            spacemouse: spacemouse::lookup(d.vendor_id(), d.product_id())
                .map(|(n, _)| n.to_string()),
        })
        .collect())
}

/// Reads a SpaceMouse: the device at `path`, or the first SpaceMouse found; calls `each`
/// with the state after every motion or button report, `count` times or until `timeout`
/// passes without a report.
pub fn read_spacemouse(
    path: Option<&str>,
    count: usize,
    timeout: Duration,
    mut each: impl FnMut(&SpaceMouseState),
) -> Result<(String, usize), DeviceError> {
    let api = hidapi::HidApi::new()?;
    let info = find_spacemouse(&api, path)?;
    let (name, kind) = spacemouse::lookup(info.vendor_id(), info.product_id())
        .unwrap_or(("HID device", ReportKind::Wired));
    let dev = info
        .open_device(&api)
        .map_err(|source| DeviceError::OpenHid {
            path: info.path().to_string_lossy().into_owned(),
            source,
        })?;
    let mut state = SpaceMouseState::default();
    let mut buf = [0u8; 64];
    let mut n = 0;
    let mut last = Instant::now();
    while n < count {
        let k = dev
            .read_timeout(&mut buf, 50)
            .map_err(|source| DeviceError::ReadHid {
                device: name.to_string(),
                source,
            })?;
        if k == 0 {
            if last.elapsed() > timeout {
                break;
            }
            continue;
        }
        last = Instant::now();
        if let Err(e) = spacemouse::apply_report(&mut state, kind, &buf[..k]) {
            tracing::debug!("{name}: {e}");
            continue;
        }
        each(&state);
        n += 1;
    }
    Ok((name.to_string(), n))
}

/// A SpaceMouse opened through hidapi, seen as a driver port: each `read` returns one HID
/// report, a read that times out is `TimedOut` (so the driver thread keeps watching its stop
/// flag), and writes are accepted and ignored (the protocol sends nothing).
pub struct HidPort {
    device: hidapi::HidDevice,
    name: String,
}

impl std::io::Read for HidPort {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        match self.device.read_timeout(buf, 20) {
            Ok(0) => Err(std::io::Error::new(
                std::io::ErrorKind::TimedOut,
                "no HID report",
            )),
            Ok(n) => Ok(n),
            Err(e) => Err(std::io::Error::other(format!("{}: {e}", self.name))),
        }
    }
}

impl std::io::Write for HidPort {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        Ok(buf.len())
    }

    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

/// The HID device at hidraw `path`, or the first SpaceMouse found; the error says which
/// was missing.
fn find_spacemouse<'a>(
    api: &'a hidapi::HidApi,
    path: Option<&str>,
) -> Result<&'a hidapi::DeviceInfo, DeviceError> {
    api.device_list()
        .find(|d| match path {
            Some(p) => d.path().to_string_lossy() == p,
            None => spacemouse::lookup(d.vendor_id(), d.product_id()).is_some(),
        })
        .ok_or_else(|| match path {
            Some(p) => DeviceError::NoHidDevice(p.to_string()),
            None => DeviceError::NoSpaceMouse,
        })
}

/// Opens the SpaceMouse at hidraw `path`, or the first SpaceMouse found, as a driver port.
/// The error says which device was missing or could not be opened.
pub fn open_spacemouse(path: Option<&str>) -> Result<Box<dyn Port>, DeviceError> {
    let api = hidapi::HidApi::new()?;
    let info = find_spacemouse(&api, path)?;
    let name = spacemouse::lookup(info.vendor_id(), info.product_id())
        .map(|(n, _)| n.to_string())
        .unwrap_or_else(|| "HID device".into());
    let device = info
        .open_device(&api)
        .map_err(|source| DeviceError::OpenHid {
            path: info.path().to_string_lossy().into_owned(),
            source,
        })?;
    Ok(Box::new(HidPort { device, name }))
}
