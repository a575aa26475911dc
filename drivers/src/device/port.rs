//! Byte streams to devices: the `Port` trait, serial ports (opening and listing), and the
//! small blocking exchanges a protocol needs while it configures its device.

use crate::device::error::DeviceError;
use serde::Serialize;
use std::io::{Read, Write};
use std::time::{Duration, Instant};

/// A byte stream to a device (a serial port, or anything readable and writable with a
/// read timeout).
pub trait Port: Read + Write + Send {}
impl<T: Read + Write + Send + ?Sized> Port for T {}

/// Opens a serial port at a baud rate, 8N1, with a short read timeout so the thread can
/// notice a stop request and a silent device.
pub fn open_serial(path: &str, baud: u32) -> Result<Box<dyn Port>, DeviceError> {
    let port = serialport::new(path, baud)
        .timeout(Duration::from_millis(20))
        .data_bits(serialport::DataBits::Eight)
        .parity(serialport::Parity::None)
        .stop_bits(serialport::StopBits::One)
        .flow_control(serialport::FlowControl::None)
        .open()
        .map_err(|source| DeviceError::OpenSerial {
            path: path.to_string(),
            source,
        })?;
    Ok(Box::new(port))
}

/// Writes a command and flushes it.
pub(crate) fn write_all(port: &mut dyn Port, bytes: &[u8]) -> Result<(), DeviceError> {
    port.write_all(bytes)
        .and_then(|_| port.flush())
        .map_err(|source| DeviceError::Write {
            bytes: bytes.to_vec(),
            source,
        })
}

/// Reads exactly `n` bytes or fails after `timeout`.
pub(crate) fn read_exact_timeout(
    port: &mut dyn Port,
    n: usize,
    timeout: Duration,
) -> Result<Vec<u8>, DeviceError> {
    let start = Instant::now();
    let mut out = Vec::with_capacity(n);
    let mut buf = [0u8; 64];
    while out.len() < n {
        if start.elapsed() > timeout {
            return Err(DeviceError::Timeout {
                got: out.len(),
                wanted: n,
            });
        }
        let want = (n - out.len()).min(buf.len());
        match port.read(&mut buf[..want]) {
            Ok(0) => return Err(DeviceError::Closed),
            Ok(k) => out.extend_from_slice(&buf[..k]),
            Err(e)
                if e.kind() == std::io::ErrorKind::TimedOut
                    || e.kind() == std::io::ErrorKind::WouldBlock => {}
            Err(e) => return Err(DeviceError::Read(e)),
        }
    }
    Ok(out)
}

/// Reads and discards whatever arrives within `quiet` (stale records of an earlier stream).
pub(crate) fn drain(port: &mut dyn Port, quiet: Duration) {
    let start = Instant::now();
    let mut buf = [0u8; 256];
    while start.elapsed() < quiet {
        match port.read(&mut buf) {
            Ok(0) => break,
            Ok(_) => {}
            Err(e)
                if e.kind() == std::io::ErrorKind::TimedOut
                    || e.kind() == std::io::ErrorKind::WouldBlock => {}
            Err(_) => break,
        }
    }
}

/// A serial port found on the system.
#[derive(Clone, Debug, Serialize)]
pub struct SerialInfo {
    /// Device path.
    pub path: String,
    /// What kind of port (USB with vendor/product, PCI, Bluetooth, unknown).
    pub kind: String,
}

/// Serial ports (scanned from sysfs; no libudev needed).
pub fn serial_ports() -> Result<Vec<SerialInfo>, DeviceError> {
    let ports = serialport::available_ports().map_err(DeviceError::ListSerial)?;
    Ok(ports
        .into_iter()
        .map(|p| SerialInfo {
            path: p.port_name,
            kind: match p.port_type {
                serialport::SerialPortType::UsbPort(u) => format!(
                    "usb {:04x}:{:04x} {}",
                    u.vid,
                    u.pid,
                    u.product.unwrap_or_default()
                ),
                serialport::SerialPortType::PciPort => "pci".into(),
                serialport::SerialPortType::BluetoothPort => "bluetooth".into(),
                serialport::SerialPortType::Unknown => "unknown".into(),
            },
        })
        .collect())
}
