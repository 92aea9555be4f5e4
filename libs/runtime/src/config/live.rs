//! `[live]`: the live view for the ground station (the `live` stage, a Foxglove WebSocket
//! server). Read by the supervisor (whether to start the stage) and by the stage itself.

use hubtrack_types::params;
use hubtrack_types::params::ParamError;
use std::net::SocketAddr;

params! {
    /// `[live]`: what the live view serves and how much of the link it may use.
    pub struct LiveConfig {
        /// Start the live-view stage with `hubtrack run` (the same as adding `"live"` to
        /// `run.stages`; `hubtrack run --live ADDR` turns it on from the command line).
        pub enabled: bool = false;
        /// `IP:PORT` the WebSocket server listens on. The protocol has no authentication: bind it
        /// to the radio or VPN interface only, never to a public one (port 0: any free port).
        pub address: String = "127.0.0.1:8765".into();
        /// Video frames sent per second at most (the camera's other frames are skipped).
        pub max_fps: f64 = 5.0, closed(0.1, 60.0);
        /// Bitrate cap of everything sent, kbit/s per client: a video frame is skipped while the
        /// last second's budget is spent (the messages are small and never skipped for it).
        pub max_kbps: f64 = 2000.0, closed(10.0, 1_000_000.0);
        /// Video frames are shrunk by a whole factor (box average) to at most this width, px.
        pub max_width: u32 = 640, closed(16, 8192);
        /// JPEG quality of the video (libjpeg's 1..100 scale).
        pub jpeg_quality: u32 = 50, closed(1, 100);
        /// Messages sent per second at most on each message channel (`/track`, `/setpoints`,
        /// `/vehicle`, ...; `/status` per stage). The overlay follows the video frames.
        pub max_message_hz: f64 = 10.0, closed(0.1, 1000.0);
        /// Messages queued per client before the oldest are dropped: a stalled or slow client
        /// loses stale messages instead of growing a queue (tuning).
        pub client_queue_messages: usize = 32, closed(2, 4096);
    }
}

impl LiveConfig {
    /// The socket address to listen on.
    pub fn socket_addr(&self) -> Result<SocketAddr, ParamError> {
        self.address.trim().parse().map_err(|e| ParamError {
            key: "live.address".into(),
            value: format!("{:?}", self.address),
            allowed: "IP:PORT, e.g. \"127.0.0.1:8765\" or \"[::1]:8765\"".into(),
            problem: Some(format!("not a socket address ({e})")),
        })
    }

    /// Checks every value; errors name the key under `live`.
    pub fn validate(&self) -> Result<(), ParamError> {
        self.check_ranges("live")?;
        self.socket_addr().map(|_| ())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn address_must_be_ip_and_port() {
        assert!(LiveConfig::default().validate().is_ok());
        for bad in ["vehicle:8765", "127.0.0.1", "", "127.0.0.1:99999"] {
            let c = LiveConfig {
                address: bad.into(),
                ..LiveConfig::default()
            };
            let e = c.validate().unwrap_err();
            assert_eq!(e.key, "live.address", "{bad}");
        }
        let v6 = LiveConfig {
            address: "[::1]:0".into(),
            ..LiveConfig::default()
        };
        assert_eq!(v6.socket_addr().unwrap().port(), 0);
    }
}
