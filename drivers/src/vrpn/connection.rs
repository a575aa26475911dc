//! A connection to a VRPN server: TCP with the cookie handshake, and a UDP socket the
//! server sends its unreliable messages (tracker reports) to when the name is not
//! `tcp://`. It reads as a byte stream of whole messages, whichever socket they came on,
//! so the device thread, the recorder and the decoder see one stream.
//!
//! troupe connects to the server's TCP port directly (as VRPN's own clients do for
//! `tcp://` names) and then, for other names, offers its UDP port with a UDP description
//! message — the setup sequence of `Format_Of_Protocol.txt`. VRPN's older way, a UDP
//! request asking the server to connect back to the client, is not used: it fails through
//! NAT and firewalls and brings nothing more.

use crate::device::error::DeviceError;
use crate::vrpn::error::VrpnError;
use crate::vrpn::name::DeviceName;
use crate::vrpn::wire::{check_cookie, encode, split_datagram, system, Framer, COOKIE};
use std::io::{self, Read, Write};
use std::net::{TcpStream, ToSocketAddrs, UdpSocket};
use std::os::fd::AsRawFd;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

/// Datagrams a connection dropped because they were not whole messages (shared with the
/// protocol, which reports them in the device's health).
#[derive(Debug, Default)]
pub struct DatagramCounters {
    /// Datagrams dropped.
    pub dropped: AtomicU64,
    /// Their bytes.
    pub dropped_bytes: AtomicU64,
}

/// An open connection to a VRPN server.
pub struct VrpnPort {
    tcp: TcpStream,
    udp: Option<UdpSocket>,
    framer: Framer,
    /// Whole messages ready for `read`, and how far they have been read.
    out: Vec<u8>,
    out_at: usize,
    counters: Arc<DatagramCounters>,
    /// How long `read` waits for either socket.
    wait: Duration,
    /// Receives one datagram (VRPN's largest message fits).
    datagram: Vec<u8>,
}

impl VrpnPort {
    /// Connects to the server `name` names, exchanges cookies (refusing another major
    /// version) and, unless the name is `tcp://`, offers a UDP port. Each step must finish
    /// within `timeout`.
    pub fn connect(
        name: &DeviceName,
        timeout: Duration,
        counters: Arc<DatagramCounters>,
    ) -> Result<VrpnPort, VrpnError> {
        let server = name.server();
        let addr = (name.host.as_str(), name.port)
            .to_socket_addrs()
            .map_err(|source| VrpnError::Resolve {
                server: server.clone(),
                source,
            })?
            .next()
            .ok_or_else(|| VrpnError::Resolve {
                server: server.clone(),
                source: io::Error::new(io::ErrorKind::NotFound, "no address"),
            })?;
        let io_err = |what: &str| {
            let what = format!("{server}: {what}");
            move |source| VrpnError::Io { what, source }
        };
        let mut tcp =
            TcpStream::connect_timeout(&addr, timeout).map_err(|source| VrpnError::Connect {
                server: server.clone(),
                source,
            })?;
        tcp.set_nodelay(true).map_err(io_err("TCP_NODELAY"))?;
        reset_on_close(&tcp).map_err(io_err("SO_LINGER"))?;
        tcp.set_write_timeout(Some(timeout))
            .map_err(io_err("write timeout"))?;
        tcp.write_all(COOKIE)
            .map_err(io_err("sending the cookie"))?;
        let cookie = read_cookie(&mut tcp, &server, timeout)?;
        check_cookie(&cookie).map_err(|e| match e {
            VrpnError::Cookie(c) => VrpnError::Cookie(format!("{c}' from {server}")),
            other => other,
        })?;
        let udp = if name.tcp_only {
            None
        } else {
            let local = tcp.local_addr().map_err(io_err("local address"))?;
            let udp = UdpSocket::bind((local.ip(), 0)).map_err(io_err("opening a UDP port"))?;
            let port = udp.local_addr().map_err(io_err("UDP port"))?.port();
            let mut host = local.ip().to_string().into_bytes();
            host.push(0);
            let (sec, usec) = now();
            tcp.write_all(&encode(
                sec,
                usec,
                i32::from(port),
                system::UDP_DESCRIPTION,
                &host,
            ))
            .map_err(io_err("sending the UDP description"))?;
            udp.set_nonblocking(true)
                .map_err(io_err("UDP non-blocking"))?;
            Some(udp)
        };
        tcp.set_nonblocking(true)
            .map_err(io_err("TCP non-blocking"))?;
        Ok(VrpnPort {
            tcp,
            udp,
            framer: Framer::default(),
            out: Vec::new(),
            out_at: 0,
            counters,
            wait: Duration::from_millis(20),
            datagram: vec![0; 65_536],
        })
    }

    /// Moves the next whole TCP message, if one is buffered, to the output.
    fn frame_tcp(&mut self) -> io::Result<bool> {
        match self.framer.next_message() {
            Ok(Some(m)) => {
                let h = m.header;
                self.out = encode(h.sec, h.usec, h.sender, h.kind, &m.payload);
                self.out_at = 0;
                Ok(true)
            }
            Ok(None) => Ok(false),
            // A length that lies leaves the TCP stream unframeable: drop the connection.
            Err(e) => Err(io::Error::new(io::ErrorKind::InvalidData, e)),
        }
    }

    /// Waits up to `self.wait` for either socket; (TCP readable, UDP readable).
    fn poll(&self) -> io::Result<(bool, bool)> {
        let mut fds = vec![libc::pollfd {
            fd: self.tcp.as_raw_fd(),
            events: libc::POLLIN,
            revents: 0,
        }];
        if let Some(u) = &self.udp {
            fds.push(libc::pollfd {
                fd: u.as_raw_fd(),
                events: libc::POLLIN,
                revents: 0,
            });
        }
        let ms = self.wait.as_millis() as libc::c_int;
        // SAFETY: `fds` is a valid array of `fds.len()` pollfd structures for the call.
        let n = unsafe { libc::poll(fds.as_mut_ptr(), fds.len() as libc::nfds_t, ms) };
        if n < 0 {
            let e = io::Error::last_os_error();
            return if e.kind() == io::ErrorKind::Interrupted {
                Ok((false, false))
            } else {
                Err(e)
            };
        }
        let ready =
            |f: &libc::pollfd| f.revents & (libc::POLLIN | libc::POLLHUP | libc::POLLERR) != 0;
        Ok((ready(&fds[0]), fds.get(1).is_some_and(ready)))
    }
}

impl Read for VrpnPort {
    /// Whole messages, TCP's first (the descriptions precede the reports they name);
    /// `WouldBlock` or `TimedOut` when nothing whole has arrived, `Ok(0)` when the server
    /// closed the connection.
    fn read(&mut self, buf: &mut [u8]) -> io::Result<usize> {
        if self.out_at >= self.out.len() && !self.frame_tcp()? {
            let (tcp, udp) = self.poll()?;
            if udp {
                if let Some(sock) = &self.udp {
                    match sock.recv(&mut self.datagram) {
                        Ok(n) => match split_datagram(&self.datagram[..n]) {
                            Ok(messages) => {
                                self.out = messages
                                    .iter()
                                    .flat_map(|m| {
                                        let h = m.header;
                                        encode(h.sec, h.usec, h.sender, h.kind, &m.payload)
                                    })
                                    .collect();
                                self.out_at = 0;
                            }
                            Err(e) => {
                                tracing::debug!("VRPN datagram of {n} bytes dropped: {e}");
                                self.counters.dropped.fetch_add(1, Ordering::Relaxed);
                                self.counters
                                    .dropped_bytes
                                    .fetch_add(n as u64, Ordering::Relaxed);
                            }
                        },
                        Err(e) if e.kind() == io::ErrorKind::WouldBlock => {}
                        // A refused or failed datagram is not the connection's end: TCP says.
                        Err(e) => tracing::debug!("VRPN UDP receive: {e}"),
                    }
                }
            }
            if self.out_at >= self.out.len() && tcp {
                let mut chunk = [0u8; 16_384];
                match self.tcp.read(&mut chunk) {
                    Ok(0) => return Ok(0),
                    Ok(n) => self.framer.push(&chunk[..n]),
                    Err(e) if e.kind() == io::ErrorKind::WouldBlock => {}
                    Err(e) => return Err(e),
                }
                self.frame_tcp()?;
            }
            if self.out_at >= self.out.len() {
                return Err(io::ErrorKind::WouldBlock.into());
            }
        }
        let n = buf.len().min(self.out.len() - self.out_at);
        buf[..n].copy_from_slice(&self.out[self.out_at..self.out_at + n]);
        self.out_at += n;
        Ok(n)
    }
}

impl Write for VrpnPort {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        // The socket is non-blocking for reads; a write waits briefly for room.
        let start = Instant::now();
        loop {
            match self.tcp.write(buf) {
                Err(e) if e.kind() == io::ErrorKind::WouldBlock => {
                    if start.elapsed() > Duration::from_secs(1) {
                        return Err(io::ErrorKind::TimedOut.into());
                    }
                    std::thread::sleep(Duration::from_millis(1));
                }
                r => return r,
            }
        }
    }

    fn flush(&mut self) -> io::Result<()> {
        self.tcp.flush()
    }
}

/// Makes closing the socket reset the connection rather than end it gracefully. When the
/// server goes away first, a graceful close would leave its side of the connection in
/// TIME_WAIT for a minute, and VRPN's server (which does not set SO_REUSEADDR on Linux)
/// could not listen on its port again when restarted; a reset frees the port at once.
fn reset_on_close(tcp: &TcpStream) -> io::Result<()> {
    let linger = libc::linger {
        l_onoff: 1,
        l_linger: 0,
    };
    // SAFETY: a valid socket, and a pointer to a `linger` of the size given.
    let r = unsafe {
        libc::setsockopt(
            tcp.as_raw_fd(),
            libc::SOL_SOCKET,
            libc::SO_LINGER,
            (&linger as *const libc::linger).cast(),
            std::mem::size_of::<libc::linger>() as libc::socklen_t,
        )
    };
    if r == 0 {
        Ok(())
    } else {
        Err(io::Error::last_os_error())
    }
}

/// Reads the peer's 24-byte cookie within `timeout`.
fn read_cookie(tcp: &mut TcpStream, server: &str, timeout: Duration) -> Result<Vec<u8>, VrpnError> {
    let deadline = Instant::now() + timeout;
    let mut cookie = vec![0u8; COOKIE.len()];
    let mut got = 0;
    while got < cookie.len() {
        let left = deadline.saturating_duration_since(Instant::now());
        let timed_out = || VrpnError::HandshakeTimeout {
            server: server.to_string(),
            timeout,
            got,
        };
        if left.is_zero() {
            return Err(timed_out());
        }
        tcp.set_read_timeout(Some(left))
            .map_err(|source| VrpnError::Io {
                what: format!("{server}: read timeout"),
                source,
            })?;
        match tcp.read(&mut cookie[got..]) {
            Ok(0) => {
                return Err(VrpnError::HandshakeClosed {
                    server: server.to_string(),
                    got,
                })
            }
            Ok(n) => got += n,
            Err(e)
                if matches!(
                    e.kind(),
                    io::ErrorKind::WouldBlock | io::ErrorKind::TimedOut
                ) =>
            {
                return Err(timed_out())
            }
            Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
            Err(source) => {
                return Err(VrpnError::Io {
                    what: format!("{server}: reading the cookie"),
                    source,
                })
            }
        }
    }
    Ok(cookie)
}

/// The wall clock as VRPN timestamps it: (seconds, microseconds) since the Unix epoch.
pub(crate) fn now() -> (u32, u32) {
    let d = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .unwrap_or_default();
    (d.as_secs() as u32, d.subsec_micros())
}

impl From<VrpnError> for DeviceError {
    fn from(e: VrpnError) -> DeviceError {
        DeviceError::Vrpn(e)
    }
}
