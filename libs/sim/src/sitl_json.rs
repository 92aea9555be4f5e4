//! ArduPilot SITL's JSON external-physics protocol (`--model JSON`), as plain data.
//!
//! SITL sends one binary servo packet per physics step to UDP port 9002 and waits for the
//! vehicle state in reply before it goes on, so the physics and the firmware advance in lock
//! step (ArduPilot `libraries/SITL/SIM_JSON.cpp`, `libraries/SITL/examples/JSON/readme.md`):
//!
//! ```text
//! uint16 magic = 18458 (16 channels) or 29569 (32 channels, SERVO_32_ENABLE = 1)
//! uint16 frame_rate     physics steps per second (SIM_RATE_HZ)
//! uint32 frame_count    +1 per step; starts again when SITL restarts
//! uint16 pwm[16 | 32]   µs
//! ```
//! little-endian. The reply is one line of JSON, framed by newlines, with `timestamp` (s of
//! physics time), `imu.gyro` (body rad/s), `imu.accel_body` (body specific force, m/s²),
//! `position` and `velocity` (NED, m and m/s, relative to SITL's home) and `quaternion`
//! (body to NED, w first).

/// Magic of the 16-channel packet.
pub const MAGIC_16: u16 = 18458;
/// Magic of the 32-channel packet.
pub const MAGIC_32: u16 = 29569;
/// The physics port SITL sends its servo packets to.
pub const DEFAULT_PORT: u16 = 9002;

/// One servo packet from SITL.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ServoPacket {
    /// Physics steps per second SITL asks for.
    pub frame_rate: u16,
    /// Step counter (starts again when SITL restarts).
    pub frame_count: u32,
    /// PWM per channel, µs (16 or 32 channels).
    pub pwm_us: Vec<u16>,
}

/// Why a datagram is not a servo packet.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum PacketError {
    /// Shorter than its magic says.
    Short {
        /// Bytes received.
        len: usize,
        /// Bytes needed.
        needed: usize,
    },
    /// The magic is neither 18458 nor 29569.
    BadMagic(u16),
    /// A frame rate of zero (no time step).
    ZeroFrameRate,
}

impl std::fmt::Display for PacketError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            PacketError::Short { len, needed } => {
                write!(f, "SITL servo packet of {len} bytes, need {needed}")
            }
            PacketError::BadMagic(m) => write!(
                f,
                "not a SITL servo packet: magic {m}, expected {MAGIC_16} or {MAGIC_32}"
            ),
            PacketError::ZeroFrameRate => f.write_str("SITL servo packet with frame rate 0"),
        }
    }
}

impl std::error::Error for PacketError {}

impl ServoPacket {
    /// Parses one datagram.
    pub fn parse(bytes: &[u8]) -> Result<ServoPacket, PacketError> {
        let u16_at = |i: usize| u16::from_le_bytes([bytes[i], bytes[i + 1]]);
        if bytes.len() < 2 {
            return Err(PacketError::Short {
                len: bytes.len(),
                needed: 2,
            });
        }
        let channels = match u16_at(0) {
            MAGIC_16 => 16,
            MAGIC_32 => 32,
            m => return Err(PacketError::BadMagic(m)),
        };
        let needed = 8 + 2 * channels;
        if bytes.len() < needed {
            return Err(PacketError::Short {
                len: bytes.len(),
                needed,
            });
        }
        let frame_rate = u16_at(2);
        if frame_rate == 0 {
            return Err(PacketError::ZeroFrameRate);
        }
        Ok(ServoPacket {
            frame_rate,
            frame_count: u32::from_le_bytes([bytes[4], bytes[5], bytes[6], bytes[7]]),
            pwm_us: (0..channels).map(|c| u16_at(8 + 2 * c)).collect(),
        })
    }

    /// The time step it asks for, s.
    pub fn dt_s(&self) -> f64 {
        1.0 / f64::from(self.frame_rate)
    }
}

/// The vehicle state SITL's sensors are simulated from.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PhysicsState {
    /// Physics time, s.
    pub timestamp_s: f64,
    /// Body rates, rad/s.
    pub gyro: [f64; 3],
    /// Specific force in body axes, m/s².
    pub accel_body: [f64; 3],
    /// NED position relative to home, m.
    pub position_ned: [f64; 3],
    /// NED velocity, m/s.
    pub velocity_ned: [f64; 3],
    /// Body-to-NED attitude, `[w, x, y, z]`.
    pub quaternion: [f64; 4],
}

impl PhysicsState {
    /// The reply line: JSON framed by newlines, as SITL reads it.
    pub fn to_json_line(&self) -> String {
        let v = |a: &[f64]| {
            a.iter()
                .map(|x| format!("{x:.9}"))
                .collect::<Vec<_>>()
                .join(",")
        };
        format!(
            "\n{{\"timestamp\":{:.6},\"imu\":{{\"gyro\":[{}],\"accel_body\":[{}]}},\"position\":[{}],\"velocity\":[{}],\"quaternion\":[{}]}}\n",
            self.timestamp_s,
            v(&self.gyro),
            v(&self.accel_body),
            v(&self.position_ned),
            v(&self.velocity_ned),
            v(&self.quaternion)
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn packet(magic: u16, rate: u16, count: u32, channels: usize) -> Vec<u8> {
        let mut b = Vec::new();
        b.extend(magic.to_le_bytes());
        b.extend(rate.to_le_bytes());
        b.extend(count.to_le_bytes());
        for c in 0..channels {
            b.extend((1000 + c as u16).to_le_bytes());
        }
        b
    }

    #[test]
    fn parses_16_and_32_channel_packets() {
        let p = ServoPacket::parse(&packet(MAGIC_16, 1200, 7, 16)).unwrap();
        assert_eq!((p.frame_rate, p.frame_count, p.pwm_us.len()), (1200, 7, 16));
        assert_eq!(p.pwm_us[3], 1003);
        assert!((p.dt_s() - 1.0 / 1200.0).abs() < 1e-15);
        let p = ServoPacket::parse(&packet(MAGIC_32, 400, 1, 32)).unwrap();
        assert_eq!(p.pwm_us.len(), 32);
    }

    #[test]
    fn rejects_what_is_not_a_packet() {
        assert_eq!(
            ServoPacket::parse(&packet(1, 400, 1, 16)),
            Err(PacketError::BadMagic(1))
        );
        assert!(matches!(
            ServoPacket::parse(&packet(MAGIC_16, 400, 1, 16)[..20]),
            Err(PacketError::Short { needed: 40, .. })
        ));
        assert_eq!(
            ServoPacket::parse(&packet(MAGIC_16, 0, 1, 16)),
            Err(PacketError::ZeroFrameRate)
        );
        assert!(ServoPacket::parse(&[]).is_err());
    }

    /// The reply is one JSON object with the fields SITL requires, framed by newlines.
    #[test]
    fn reply_is_framed_json_with_the_required_fields() {
        let s = PhysicsState {
            timestamp_s: 1.5,
            gyro: [0.1, 0.0, 0.0],
            accel_body: [0.0, 0.0, -9.8],
            position_ned: [1.0, 2.0, -3.0],
            velocity_ned: [0.0; 3],
            quaternion: [1.0, 0.0, 0.0, 0.0],
        };
        let line = s.to_json_line();
        assert!(line.starts_with('\n') && line.ends_with('\n'));
        let v: serde_json::Value = serde_json::from_str(line.trim()).unwrap();
        assert_eq!(v["timestamp"], 1.5);
        assert_eq!(v["imu"]["accel_body"][2], -9.8);
        assert_eq!(v["position"][2], -3.0);
        assert_eq!(v["quaternion"][0], 1.0);
        assert!(v["velocity"].is_array() && v["imu"]["gyro"].is_array());
    }
}
