//! Transports: where a link goes ([`Endpoint`]) and the open link ([`Link`]).

use std::fmt;
use std::io::{ErrorKind, Read, Write};
use std::net::{Ipv4Addr, Ipv6Addr, SocketAddr, ToSocketAddrs, UdpSocket};
use std::str::FromStr;
use std::time::{Duration, Instant, SystemTime};

use mavlink::dialects::common::MavMessage;
use mavlink::{MavHeader, Message};

use crate::parser::{encode_v2, FrameParser, LinkStats};
use crate::peer::{AutopilotId, PeerLock};
use crate::signing::{signing_timestamp, Refusal, Signing};

/// Receive buffer size: the largest UDP datagram.
const READ_BUF_LEN: usize = 65_536;
/// After data arrived, how many more immediately available reads one [`Link::recv`] takes, so a
/// flood cannot keep it from returning.
const MAX_DRAIN_READS: usize = 64;
/// How long a serial write may block (the port is not read by the other side, a USB CDC device
/// is gone) before it fails.
const SERIAL_WRITE_TIMEOUT: Duration = Duration::from_millis(100);
/// The forms an endpoint string takes, for error messages.
const ENDPOINT_FORMS: &str = "udpin:ADDR:PORT, udpout:ADDR:PORT or serial:PATH:BAUD";

/// Where the link goes.
///
/// Parsed from (and displayed as) `udpin:0.0.0.0:14550`, `udpout:127.0.0.1:14550` or
/// `serial:/dev/ttyACM0:921600`. Host names are resolved when parsing (first address).
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Endpoint {
    /// Bind this address and listen; replies go to the address the last datagram came from.
    UdpIn(SocketAddr),
    /// Send to this address; replies are received on an ephemeral local port.
    UdpOut(SocketAddr),
    /// A serial device at this baud rate, 8N1, no flow control.
    Serial {
        /// Device path, e.g. `/dev/ttyACM0`.
        path: String,
        /// Baud rate, e.g. 921600.
        baud: u32,
    },
}

impl Endpoint {
    fn bad(input: &str, reason: impl Into<String>) -> LinkError {
        LinkError::BadEndpoint {
            input: input.to_string(),
            reason: reason.into(),
        }
    }

    fn parse_addr(input: &str, addr: &str) -> Result<SocketAddr, LinkError> {
        if let Ok(a) = addr.parse::<SocketAddr>() {
            return Ok(a);
        }
        let mut addrs = addr
            .to_socket_addrs()
            .map_err(|e| Self::bad(input, format!("address {addr:?}: {e}")))?;
        addrs
            .next()
            .ok_or_else(|| Self::bad(input, format!("address {addr:?} resolves to nothing")))
    }
}

impl FromStr for Endpoint {
    type Err = LinkError;

    fn from_str(s: &str) -> Result<Self, LinkError> {
        let (kind, rest) = s
            .split_once(':')
            .ok_or_else(|| Self::bad(s, "no transport prefix"))?;
        match kind {
            "udpin" => Ok(Endpoint::UdpIn(Self::parse_addr(s, rest)?)),
            "udpout" => Ok(Endpoint::UdpOut(Self::parse_addr(s, rest)?)),
            "serial" => {
                let (path, baud) = rest
                    .rsplit_once(':')
                    .ok_or_else(|| Self::bad(s, "no baud rate"))?;
                if path.is_empty() {
                    return Err(Self::bad(s, "empty device path"));
                }
                let baud = baud.parse::<u32>().ok().filter(|&b| b > 0).ok_or_else(|| {
                    Self::bad(s, format!("baud rate {baud:?} is not a positive integer"))
                })?;
                Ok(Endpoint::Serial {
                    path: path.to_string(),
                    baud,
                })
            }
            other => Err(Self::bad(s, format!("unknown transport {other:?}"))),
        }
    }
}

impl fmt::Display for Endpoint {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Endpoint::UdpIn(a) => write!(f, "udpin:{a}"),
            Endpoint::UdpOut(a) => write!(f, "udpout:{a}"),
            Endpoint::Serial { path, baud } => write!(f, "serial:{path}:{baud}"),
        }
    }
}

impl serde::Serialize for Endpoint {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.collect_str(self)
    }
}

impl<'de> serde::Deserialize<'de> for Endpoint {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let s = String::deserialize(d)?;
        s.parse().map_err(serde::de::Error::custom)
    }
}

impl Endpoint {
    /// Checks the config key `key` (`control.link`, `sim.link`) holding `text`: the endpoint, or
    /// an error naming the key, what is wrong and the forms an endpoint takes.
    pub fn of_config(
        key: &str,
        text: &str,
    ) -> Result<Endpoint, hubtrack_types::params::ParamError> {
        text.parse()
            .map_err(|e| hubtrack_types::params::ParamError {
                key: key.into(),
                value: format!("{text:?}"),
                allowed: ENDPOINT_FORMS.into(),
                problem: Some(match e {
                    LinkError::BadEndpoint { reason, .. } => reason,
                    other => other.to_string(),
                }),
            })
    }
}

/// Why a link could not be set up or used.
#[derive(Debug, thiserror::Error)]
pub enum LinkError {
    /// The endpoint string is malformed.
    #[error("endpoint {input:?}: {reason} (expected {ENDPOINT_FORMS})", ENDPOINT_FORMS = ENDPOINT_FORMS)]
    BadEndpoint {
        /// The string as given.
        input: String,
        /// What is wrong with it.
        reason: String,
    },
    /// The UDP socket could not be bound.
    #[error("udp bind {addr}: {cause}")]
    Bind {
        /// The address we tried to bind.
        addr: SocketAddr,
        /// The OS error (in the message, so not a chained `source`).
        cause: std::io::Error,
    },
    /// The serial port could not be opened or configured.
    #[error("serial port {path}: {cause}")]
    Serial {
        /// Device path.
        path: String,
        /// The error from the serial port library (in the message, so not a chained `source`).
        cause: serialport::Error,
    },
    /// Sending or receiving failed on an open link.
    #[error("{endpoint}: {op}: {cause}")]
    Io {
        /// The link's endpoint.
        endpoint: Endpoint,
        /// What we were doing (`send`, `receive`, ...).
        op: &'static str,
        /// The OS error (not a `source`: the message already says it, and error chains would
        /// print it twice).
        cause: std::io::Error,
    },
}

enum Transport {
    Udp {
        socket: UdpSocket,
        /// Where frames are sent: the fixed target (udpout) or the last datagram's source (udpin).
        peer: Option<SocketAddr>,
        /// udpin: follow the source of received datagrams.
        follow_peer: bool,
    },
    Serial(Box<dyn serialport::SerialPort>),
}

/// An open link (UDP or serial) with a frame parser and counters.
///
/// Received bytes go through one [`FrameParser`] in arrival order; on UDP that joins datagrams
/// into one stream, which is harmless because MAVLink senders put whole frames in each datagram.
/// Outgoing headers are sent as given (the caller numbers the sequence).
pub struct Link {
    endpoint: Endpoint,
    transport: Transport,
    parser: FrameParser,
    read_buf: Vec<u8>,
    bytes_out: u64,
    frames_out: u64,
    unsent_frames: u64,
    /// Whom to expect (see [`Link::expect_autopilot`]).
    autopilot: Option<AutopilotId>,
    /// udpin: the reply address, set and moved only by frames of the autopilot.
    peer_lock: PeerLock<SocketAddr>,
    /// MAVLink 2 signing, when a key is configured (see [`Link::enable_signing`]).
    signing: Option<Signing>,
    /// Frames refused by signing, per [`Refusal`] cause.
    refused: [u64; Refusal::ALL.len()],
}

impl fmt::Debug for Link {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Link")
            .field("endpoint", &self.endpoint)
            .field("peer", &self.peer())
            .field("stats", &self.stats())
            .finish()
    }
}

impl Link {
    /// Opens the link: binds the UDP socket or opens the serial port.
    pub fn open(endpoint: &Endpoint) -> Result<Link, LinkError> {
        let transport = match endpoint {
            Endpoint::UdpIn(addr) => Transport::Udp {
                socket: UdpSocket::bind(addr)
                    .map_err(|cause| LinkError::Bind { addr: *addr, cause })?,
                peer: None,
                follow_peer: true,
            },
            Endpoint::UdpOut(target) => {
                // Unconnected, so that ICMP "port unreachable" while the other side is not up
                // yet does not turn into errors on later calls.
                let any: SocketAddr = if target.is_ipv4() {
                    (Ipv4Addr::UNSPECIFIED, 0).into()
                } else {
                    (Ipv6Addr::UNSPECIFIED, 0).into()
                };
                Transport::Udp {
                    socket: UdpSocket::bind(any)
                        .map_err(|cause| LinkError::Bind { addr: any, cause })?,
                    peer: Some(*target),
                    follow_peer: false,
                }
            }
            Endpoint::Serial { path, baud } => {
                let port = serialport::new(path, *baud)
                    .data_bits(serialport::DataBits::Eight)
                    .parity(serialport::Parity::None)
                    .stop_bits(serialport::StopBits::One)
                    .flow_control(serialport::FlowControl::None)
                    .open()
                    .map_err(|cause| LinkError::Serial {
                        path: path.clone(),
                        cause,
                    })?;
                Transport::Serial(port)
            }
        };
        Ok(Link {
            endpoint: endpoint.clone(),
            transport,
            parser: FrameParser::new(),
            read_buf: vec![0; READ_BUF_LEN],
            bytes_out: 0,
            frames_out: 0,
            unsent_frames: 0,
            autopilot: None,
            peer_lock: PeerLock::default(),
            signing: None,
            refused: [0; Refusal::ALL.len()],
        })
    }

    fn io_error(&self, op: &'static str, cause: std::io::Error) -> LinkError {
        LinkError::Io {
            endpoint: self.endpoint.clone(),
            op,
            cause,
        }
    }

    /// Encodes `msg` as one MAVLink 2 frame (see [`encode_v2`]), signed when signing is on, and
    /// sends it.
    ///
    /// On a `udpin` link that has not received a datagram yet there is nowhere to send: the frame
    /// is dropped, `Ok` is returned, and it counts in [`Link::unsent_frames`], not in
    /// `frames_out`/`bytes_out`.
    pub fn send(&mut self, header: MavHeader, msg: &MavMessage) -> Result<(), LinkError> {
        let frame = match &mut self.signing {
            Some(signing) => signing.encode(header, msg, signing_timestamp(SystemTime::now())),
            None => encode_v2(header, msg),
        };
        let result = match &mut self.transport {
            Transport::Udp { socket, peer, .. } => match peer {
                Some(peer) => socket.send_to(&frame, *peer).map(|_| ()),
                None => {
                    self.unsent_frames += 1;
                    return Ok(());
                }
            },
            Transport::Serial(port) => port
                .set_timeout(SERIAL_WRITE_TIMEOUT)
                .map_err(std::io::Error::from)
                .and_then(|()| port.write_all(&frame)),
        };
        result.map_err(|e| self.io_error("send", e))?;
        self.bytes_out += frame.len() as u64;
        self.frames_out += 1;
        Ok(())
    }

    /// One read waiting at most `timeout`; returns the number of bytes (0: nothing arrived).
    /// On `udpin`, `source` is set to the datagram's sender.
    fn read_some(
        &mut self,
        timeout: Duration,
        source: &mut Option<SocketAddr>,
    ) -> Result<usize, LinkError> {
        let result = match &mut self.transport {
            Transport::Udp {
                socket,
                follow_peer,
                ..
            } => {
                // A zero read timeout means "block forever" to the OS, and a tiny one still
                // waits for the next scheduler tick (1 µs measured 8 ms here), which stalled
                // control's loop. So "only what is waiting" is a non-blocking read; the socket
                // goes back to blocking at once, for sends and timed reads.
                let received = if timeout.is_zero() {
                    socket.set_nonblocking(true).and_then(|()| {
                        let r = socket.recv_from(&mut self.read_buf);
                        socket.set_nonblocking(false).and(r)
                    })
                } else {
                    socket
                        .set_read_timeout(Some(timeout))
                        .and_then(|()| socket.recv_from(&mut self.read_buf))
                };
                received.map(|(n, from)| {
                    if *follow_peer {
                        *source = Some(from);
                    }
                    n
                })
            }
            Transport::Serial(port) => match port.set_timeout(timeout) {
                Err(e) => Err(std::io::Error::from(e)),
                Ok(()) => port.read(&mut self.read_buf),
            },
        };
        match result {
            Ok(n) => Ok(n),
            Err(e)
                if matches!(
                    e.kind(),
                    ErrorKind::WouldBlock | ErrorKind::TimedOut | ErrorKind::Interrupted
                ) =>
            {
                Ok(0)
            }
            Err(e) => Err(self.io_error("receive", e)),
        }
    }

    /// Waits at most `timeout` for data and returns the frames it completes (may be empty).
    ///
    /// Returns as soon as at least one frame is complete (after also taking whatever else is
    /// already waiting), or when `timeout` has passed. A zero timeout only takes what is waiting.
    pub fn recv(&mut self, timeout: Duration) -> Result<Vec<(MavHeader, MavMessage)>, LinkError> {
        let deadline = Instant::now() + timeout;
        let mut frames = Vec::new();
        loop {
            let remaining = deadline.saturating_duration_since(Instant::now());
            let mut from = None;
            let n = self.read_some(remaining, &mut from)?;
            if n > 0 {
                self.take(n, from, &mut frames);
                for _ in 0..MAX_DRAIN_READS {
                    let n = self.read_some(Duration::ZERO, &mut from)?;
                    if n == 0 {
                        break;
                    }
                    self.take(n, from, &mut frames);
                }
            }
            if !frames.is_empty() || remaining.is_zero() || Instant::now() >= deadline {
                return Ok(frames);
            }
        }
    }

    /// Parses `n` received bytes; on `udpin`, lets the frames of the autopilot in them set the
    /// reply address.
    fn take(
        &mut self,
        n: usize,
        from: Option<SocketAddr>,
        frames: &mut Vec<(MavHeader, MavMessage)>,
    ) {
        let mut new = Vec::new();
        let now = signing_timestamp(SystemTime::now());
        let (signing, refused) = (&mut self.signing, &mut self.refused);
        self.parser
            .push_each(&self.read_buf[..n], |raw, header, msg| match signing {
                Some(s) => match s.verify(raw, now) {
                    Ok(()) => new.push((header, msg)),
                    Err(why) => {
                        refused[why.index()] += 1;
                        // Once per cause: a spoofer must not flood the log.
                        if refused[why.index()] == 1 {
                            log::warn!(
                                "MAVLink signing: refused {} from system {} component {} ({}); further ones are only counted",
                                msg.message_name(),
                                header.system_id,
                                header.component_id,
                                why.describe()
                            );
                        }
                    }
                },
                None => new.push((header, msg)),
            });
        // Only frames that passed signing may set the reply address.
        if let (Some(from), Transport::Udp { peer, .. }) = (from, &mut self.transport) {
            self.peer_lock
                .observe(from, new.iter().map(|(h, _)| h), self.autopilot);
            *peer = self.peer_lock.peer;
        }
        frames.extend(new);
    }

    /// Turns MAVLink 2 signing on: every frame sent is signed, and received frames that are not
    /// signed with the same key or replay an old timestamp are refused (counted in
    /// [`LinkStats`], the first of each cause logged) before anything else sees them.
    pub fn enable_signing(&mut self, signing: Signing) {
        self.signing = Some(signing);
    }

    /// Takes heartbeats for replies only from `autopilot`: on `udpin`, the reply address is the
    /// one its frames come from, never moved by other senders or garbage. Without it, the first
    /// sender of any valid frame sets the address.
    pub fn expect_autopilot(&mut self, autopilot: AutopilotId) {
        self.autopilot = Some(autopilot);
    }

    /// Datagrams from other addresses that carried no frame of the autopilot (`udpin`): they did
    /// not move the reply address.
    pub fn refused_datagrams(&self) -> u64 {
        self.peer_lock.refused
    }

    /// Counters of the parser plus what was sent.
    pub fn stats(&self) -> LinkStats {
        LinkStats {
            bytes_out: self.bytes_out,
            frames_out: self.frames_out,
            unsigned_refused: self.refused[Refusal::Unsigned.index()],
            bad_signatures: self.refused[Refusal::BadSignature.index()],
            old_timestamps: self.refused[Refusal::OldTimestamp.index()],
            ..self.parser.stats()
        }
    }

    /// Frames [`Link::send`] dropped because a `udpin` link had no peer yet.
    pub fn unsent_frames(&self) -> u64 {
        self.unsent_frames
    }

    /// The local socket address (UDP only).
    pub fn local_addr(&self) -> Option<SocketAddr> {
        match &self.transport {
            Transport::Udp { socket, .. } => socket.local_addr().ok(),
            Transport::Serial(_) => None,
        }
    }

    /// Where frames go (UDP only): the udpout target, or the source of the last datagram on udpin.
    pub fn peer(&self) -> Option<SocketAddr> {
        match &self.transport {
            Transport::Udp { peer, .. } => *peer,
            Transport::Serial(_) => None,
        }
    }

    /// The endpoint this link was opened with.
    pub fn endpoint(&self) -> &Endpoint {
        &self.endpoint
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_support::*;
    use crate::{companion_heartbeat, Identity};

    const WAIT: Duration = Duration::from_secs(2);

    #[test]
    fn endpoint_strings() {
        for s in [
            "udpin:0.0.0.0:14550",
            "udpout:127.0.0.1:14551",
            "udpin:[::1]:14550",
            "serial:/dev/ttyACM0:921600",
            "serial:/dev/serial/by-id/usb-ArduPilot:with:colons:57600",
        ] {
            let e: Endpoint = s.parse().unwrap();
            assert_eq!(e.to_string(), s);
        }
        assert_eq!(
            "serial:/dev/ttyUSB0:57600".parse::<Endpoint>().unwrap(),
            Endpoint::Serial {
                path: "/dev/ttyUSB0".into(),
                baud: 57600
            }
        );
        assert_eq!(
            "udpout:localhost:14550"
                .parse::<Endpoint>()
                .unwrap()
                .to_string()
                .rsplit(':')
                .next(),
            Some("14550")
        );
        for bad in [
            "",
            "udp:1.2.3.4:5",
            "udpin:1.2.3.4",
            "tcp:1.2.3.4:5",
            "serial:/dev/ttyACM0",
            "serial:/dev/ttyACM0:fast",
            "serial:/dev/ttyACM0:0",
            "serial::9600",
        ] {
            let err = bad.parse::<Endpoint>().unwrap_err().to_string();
            assert!(
                err.contains(&format!("{bad:?}")) && err.contains("udpin:ADDR:PORT"),
                "{err}"
            );
        }
        let json =
            serde_json::to_string(&Endpoint::UdpIn("0.0.0.0:14550".parse().unwrap())).unwrap();
        assert_eq!(json, "\"udpin:0.0.0.0:14550\"");
        assert!(serde_json::from_str::<Endpoint>("\"serial:x\"").is_err());
    }

    #[test]
    fn udp_exchange_both_ways() {
        let mut server = Link::open(&"udpin:127.0.0.1:0".parse().unwrap()).unwrap();
        let port = server.local_addr().unwrap().port();
        assert_ne!(port, 0);
        let mut client = Link::open(&format!("udpout:127.0.0.1:{port}").parse().unwrap()).unwrap();
        assert_eq!(server.peer(), None);

        let me = Identity {
            system_id: 1,
            component_id: 191,
        };
        client.send(me.header(0), &companion_heartbeat()).unwrap();
        client.send(me.header(1), &companion_heartbeat()).unwrap();
        let mut got = Vec::new();
        let t = Instant::now();
        while got.len() < 2 && t.elapsed() < WAIT {
            got.extend(server.recv(WAIT).unwrap());
        }
        assert_eq!(
            got,
            vec![
                (me.header(0), companion_heartbeat()),
                (me.header(1), companion_heartbeat())
            ]
        );
        assert_eq!(
            server.peer(),
            client
                .local_addr()
                .map(|a| SocketAddr::from(([127, 0, 0, 1], a.port())))
        );

        let (h, m) = sample_messages()[1].clone();
        server.send(h, &m).unwrap();
        assert_eq!(client.recv(WAIT).unwrap(), vec![(h, m)]);

        let (c, s) = (client.stats(), server.stats());
        assert_eq!(
            (c.frames_out, c.frames_in, s.frames_in, s.frames_out),
            (2, 1, 2, 1)
        );
        assert_eq!((c.bytes_out, c.bytes_in), (s.bytes_in, s.bytes_out));
        assert_eq!(
            server.endpoint(),
            &Endpoint::UdpIn(([127, 0, 0, 1], 0).into())
        );
    }

    #[test]
    fn udpin_without_peer_drops_silently() {
        let mut server = Link::open(&"udpin:127.0.0.1:0".parse().unwrap()).unwrap();
        server
            .send(header(1, 1, 0), &companion_heartbeat())
            .unwrap();
        assert_eq!(server.unsent_frames(), 1);
        assert_eq!(
            (server.stats().frames_out, server.stats().bytes_out),
            (0, 0)
        );
    }

    #[test]
    fn recv_waits_at_most_the_timeout() {
        let mut server = Link::open(&"udpin:127.0.0.1:0".parse().unwrap()).unwrap();
        let t = Instant::now();
        assert!(server.recv(Duration::ZERO).unwrap().is_empty());
        assert!(t.elapsed() < Duration::from_millis(50));
        let t = Instant::now();
        assert!(server.recv(Duration::from_millis(100)).unwrap().is_empty());
        let waited = t.elapsed();
        assert!(
            waited >= Duration::from_millis(95) && waited < Duration::from_secs(1),
            "{waited:?}"
        );
    }

    #[test]
    fn a_zero_timeout_takes_what_is_waiting_without_waiting_for_a_tick() {
        let mut server = Link::open(&"udpin:127.0.0.1:0".parse().unwrap()).unwrap();
        let port = server.local_addr().unwrap().port();
        let mut client = Link::open(&format!("udpout:127.0.0.1:{port}").parse().unwrap()).unwrap();
        // Idle: each read returns at once (a 1 µs socket timeout waited for the next scheduler
        // tick, 4-10 ms, on every call: 200 of them took seconds).
        let t = Instant::now();
        for _ in 0..200 {
            assert!(server.recv(Duration::ZERO).unwrap().is_empty());
        }
        assert!(
            t.elapsed() < Duration::from_millis(200),
            "{:?}",
            t.elapsed()
        );
        // What is waiting is taken.
        let me = Identity {
            system_id: 1,
            component_id: 191,
        };
        client.send(me.header(0), &companion_heartbeat()).unwrap();
        let t = Instant::now();
        let mut got = Vec::new();
        while got.is_empty() && t.elapsed() < WAIT {
            got = server.recv(Duration::ZERO).unwrap();
        }
        assert_eq!(got, vec![(me.header(0), companion_heartbeat())]);
        // The socket blocks again: replies go out, timed reads wait.
        server.send(me.header(1), &companion_heartbeat()).unwrap();
        assert_eq!(
            client.recv(WAIT).unwrap(),
            vec![(me.header(1), companion_heartbeat())]
        );
    }

    #[test]
    fn udpin_replies_only_to_the_autopilot() {
        use crate::test_support::{autopilot_heartbeat, header};
        let mut server = Link::open(&"udpin:127.0.0.1:0".parse().unwrap()).unwrap();
        server.expect_autopilot(AutopilotId {
            system_id: 1,
            component_id: 1,
        });
        let to = server.local_addr().unwrap();
        let autopilot = UdpSocket::bind("127.0.0.1:0").unwrap();
        let stranger = UdpSocket::bind("127.0.0.1:0").unwrap();
        let hb = |sys, seq| crate::encode_v2(header(sys, 1, seq), &autopilot_heartbeat(true, 4));
        let drain = |server: &mut Link, n: usize| {
            let t = Instant::now();
            let mut got = 0;
            while got < n && t.elapsed() < WAIT {
                got += server.recv(Duration::from_millis(20)).unwrap().len();
            }
        };
        // A stranger speaks first: no reply address yet.
        stranger.send_to(&hb(99, 0), to).unwrap();
        drain(&mut server, 1);
        assert_eq!(server.peer(), None);
        autopilot.send_to(&hb(1, 0), to).unwrap();
        drain(&mut server, 1);
        assert_eq!(server.peer(), Some(autopilot.local_addr().unwrap()));
        // Garbage and another system afterwards do not move it.
        stranger.send_to(b"\xfd garbage", to).unwrap();
        stranger.send_to(&hb(99, 1), to).unwrap();
        drain(&mut server, 1);
        std::thread::sleep(Duration::from_millis(50));
        let _ = server.recv(Duration::from_millis(50)).unwrap();
        assert_eq!(server.peer(), Some(autopilot.local_addr().unwrap()));
        assert!(
            server.refused_datagrams() >= 2,
            "{}",
            server.refused_datagrams()
        );
    }

    #[test]
    fn with_signing_only_signed_frames_of_the_key_pass_and_set_the_peer() {
        use crate::test_support::{autopilot_heartbeat, header};
        use crate::{Signing, SigningKey};
        let key = SigningKey::from_passphrase("hubtrack test");
        let mut server = Link::open(&"udpin:127.0.0.1:0".parse().unwrap()).unwrap();
        server.enable_signing(Signing::new(key.clone(), 0));
        server.expect_autopilot(AutopilotId {
            system_id: 1,
            component_id: 1,
        });
        let port = server.local_addr().unwrap().port();
        let to = format!("udpout:127.0.0.1:{port}").parse().unwrap();
        let mut autopilot = Link::open(&to).unwrap();
        autopilot.enable_signing(Signing::new(key, 1));
        let mut unsigned = Link::open(&to).unwrap();
        let mut wrong = Link::open(&to).unwrap();
        wrong.enable_signing(Signing::new(SigningKey::from_passphrase("guess"), 1));
        let hb = autopilot_heartbeat(true, 4);
        // Spoofers with the autopilot's ids speak first: nothing passes, no reply address.
        unsigned.send(header(1, 1, 0), &hb).unwrap();
        wrong.send(header(1, 1, 0), &hb).unwrap();
        let mut got = Vec::new();
        let t = Instant::now();
        while server.stats().frames_in < 2 && t.elapsed() < WAIT {
            got.extend(server.recv(Duration::from_millis(20)).unwrap());
        }
        assert!(got.is_empty(), "{got:?}");
        assert_eq!(server.peer(), None);
        let s = server.stats();
        assert_eq!((s.unsigned_refused, s.bad_signatures), (1, 1));
        // The autopilot's signed heartbeat passes and sets the reply address.
        autopilot.send(header(1, 1, 1), &hb).unwrap();
        let t = Instant::now();
        while got.is_empty() && t.elapsed() < WAIT {
            got.extend(server.recv(Duration::from_millis(20)).unwrap());
        }
        assert_eq!(got, vec![(header(1, 1, 1), hb.clone())]);
        assert_eq!(
            server.peer().map(|a| a.port()),
            autopilot.local_addr().map(|a| a.port())
        );
        // Our reply is signed: the autopilot's signing accepts it, an unsigned link would not.
        server.send(header(1, 191, 0), &hb).unwrap();
        assert_eq!(autopilot.recv(WAIT).unwrap(), vec![(header(1, 191, 0), hb)]);
        assert_eq!(autopilot.stats().unsigned_refused, 0);
    }

    #[test]
    fn garbage_datagrams_are_counted() {
        let mut server = Link::open(&"udpin:127.0.0.1:0".parse().unwrap()).unwrap();
        let raw = UdpSocket::bind("127.0.0.1:0").unwrap();
        let to = server.local_addr().unwrap();
        raw.send_to(b"hello", to).unwrap();
        let (h, m) = sample_messages()[0].clone();
        raw.send_to(&crate::encode_v2(h, &m), to).unwrap();
        let mut got = Vec::new();
        let t = Instant::now();
        while got.is_empty() && t.elapsed() < WAIT {
            got.extend(server.recv(WAIT).unwrap());
        }
        assert_eq!(got, vec![(h, m)]);
        assert_eq!(server.stats().garbage_bytes, 5);
    }

    #[test]
    fn bind_conflict_names_the_address() {
        let first = Link::open(&"udpin:127.0.0.1:0".parse().unwrap()).unwrap();
        let addr = first.local_addr().unwrap();
        let err = Link::open(&Endpoint::UdpIn(addr)).unwrap_err().to_string();
        assert!(err.contains(&addr.to_string()), "{err}");
    }

    #[test]
    fn missing_serial_port_names_the_path() {
        let err = Link::open(&"serial:/dev/hubtrack-no-such-tty:921600".parse().unwrap())
            .unwrap_err()
            .to_string();
        assert!(
            err.starts_with("serial port /dev/hubtrack-no-such-tty: "),
            "{err}"
        );
    }

    #[test]
    fn serial_over_a_pty_pair() {
        let (mut master, slave) = serialport::TTYPort::pair().expect("pty pair");
        let path = serialport::SerialPort::name(&slave).expect("pty name");
        let mut link = Link::open(&Endpoint::Serial {
            path,
            baud: 921_600,
        })
        .unwrap();
        assert_eq!(link.local_addr(), None);

        let (h, m) = sample_messages()[1].clone();
        let frame = crate::encode_v2(h, &m);
        // Split in two writes, with noise before it.
        master.write_all(b"\x00noise").unwrap();
        master.write_all(&frame[..7]).unwrap();
        master.flush().unwrap();
        assert!(link.recv(Duration::from_millis(50)).unwrap().is_empty());
        master.write_all(&frame[7..]).unwrap();
        let mut got = Vec::new();
        let t = Instant::now();
        while got.is_empty() && t.elapsed() < WAIT {
            got.extend(link.recv(WAIT).unwrap());
        }
        assert_eq!(got, vec![(h, m)]);
        assert_eq!(link.stats().garbage_bytes, 6);

        let (h, m) = sample_messages()[0].clone();
        link.send(h, &m).unwrap();
        let sent = crate::encode_v2(h, &m);
        let mut echo = vec![0; sent.len()];
        serialport::SerialPort::set_timeout(&mut master, WAIT).unwrap();
        master.read_exact(&mut echo).unwrap();
        assert_eq!(echo, sent);
        assert_eq!(link.stats().frames_out, 1);
        drop(slave);
    }
}
