//! V4L2 camera source. Verified on hardware only: CI machines have no V4L2 devices, so the
//! negotiation ([`check_granted`]) and conversion ([`crate::convert`]) logic is unit-tested and the
//! device I/O is exercised through its error paths (missing device).

use crate::config::{V4lConfig, V4lFormat};
use crate::convert::yuyv_to_bgr;
use crate::{CaptureError, FrameInfo, FrameSink, FrameSource, Step};
use hubtrack_types::time::monotonic_ns;
use hubtrack_types::{FrameSourceKind, FrameTruth, PixelFormat};
use opencv::core::{Mat, Vector};
use opencv::imgcodecs;
use std::io;
use std::path::{Path, PathBuf};
use v4l::buffer::Type;
use v4l::control::{Control, Value};
use v4l::io::mmap::Stream;
use v4l::io::traits::CaptureStream;
use v4l::video::Capture;
use v4l::{Device, FourCC};

/// `V4L2_CID_EXPOSURE_AUTO` (menu) and its manual setting.
const CID_EXPOSURE_AUTO: u32 = 0x009a_0901;
const EXPOSURE_MANUAL: i64 = 1;
const EXPOSURE_APERTURE_PRIORITY: i64 = 3;
/// `V4L2_CID_EXPOSURE_ABSOLUTE`, in units of 100 µs.
const CID_EXPOSURE_ABSOLUTE: u32 = 0x009a_0902;
const EXPOSURE_UNIT_US: u32 = 100;
/// How long to wait for a frame before reporting the camera as stalled.
const DEQUEUE_TIMEOUT_MS: u64 = 2000;

/// What the driver granted after negotiation.
#[derive(Debug, Clone, PartialEq)]
pub struct Granted {
    /// Width, px.
    pub width: u32,
    /// Height, px.
    pub height: u32,
    /// FourCC as text (`MJPG`, `YUYV`, ...).
    pub fourcc: String,
    /// Bytes per row.
    pub stride: u32,
    /// Frame rate, if the driver reports one.
    pub fps: Option<f64>,
}

/// Checks what the driver granted against the request: an unconvertible format is an error,
/// any other difference is a warning (returned for the log).
pub fn check_granted(
    path: &Path,
    req: &V4lConfig,
    granted: &Granted,
) -> Result<(Pixel, Vec<String>), CaptureError> {
    let pixel = match granted.fourcc.as_str() {
        "MJPG" | "JPEG" => Pixel::Mjpg,
        "YUYV" => Pixel::Yuyv,
        other => {
            return Err(CaptureError::UnsupportedFormat {
                path: path.into(),
                fourcc: other.into(),
            })
        }
    };
    let mut warnings = Vec::new();
    let wanted = fourcc_text(req.format);
    if granted.fourcc != wanted && !(wanted == "MJPG" && granted.fourcc == "JPEG") {
        warnings.push(format!(
            "asked for {wanted}, driver granted {}",
            granted.fourcc
        ));
    }
    if (granted.width, granted.height) != (req.width, req.height) {
        warnings.push(format!(
            "asked for {}x{}, driver granted {}x{}",
            req.width, req.height, granted.width, granted.height
        ));
    }
    if let Some(fps) = granted.fps {
        if (fps - req.fps).abs() > 0.5 {
            warnings.push(format!(
                "asked for {} fps, driver granted {fps:.2} fps",
                req.fps
            ));
        }
    }
    if pixel == Pixel::Yuyv && granted.stride < granted.width * 2 {
        return Err(CaptureError::Device {
            path: path.into(),
            what: "format",
            reason: format!(
                "YUYV stride {} below 2*width {}",
                granted.stride,
                granted.width * 2
            ),
        });
    }
    Ok((pixel, warnings))
}

/// Pixel encoding delivered by the camera.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Pixel {
    /// Motion JPEG.
    Mjpg,
    /// YUYV 4:2:2.
    Yuyv,
}

fn fourcc_text(f: V4lFormat) -> &'static str {
    match f {
        V4lFormat::Mjpg => "MJPG",
        V4lFormat::Yuyv => "YUYV",
    }
}

/// Maps an OS error on `path` to a clear capture error.
fn device_error(path: &Path, what: &'static str, e: io::Error) -> CaptureError {
    match e.raw_os_error() {
        Some(2) => CaptureError::DeviceNotFound { path: path.into() }, // ENOENT
        Some(16) => CaptureError::DeviceBusy { path: path.into() },    // EBUSY
        _ => CaptureError::Device {
            path: path.into(),
            what,
            reason: e.to_string(),
        },
    }
}

/// A V4L2 camera streaming through mmap buffers.
pub struct V4lSource {
    path: PathBuf,
    stream: Stream<'static>,
    granted: Granted,
    pixel: Pixel,
    decoded: Mat,
}

impl V4lSource {
    /// Opens the device, negotiates format, size, rate and exposure, and starts streaming.
    pub fn open(cfg: &V4lConfig) -> Result<V4lSource, CaptureError> {
        let path = cfg.device.clone();
        if !path.exists() {
            return Err(CaptureError::DeviceNotFound { path });
        }
        let dev = Device::with_path(&path).map_err(|e| device_error(&path, "open", e))?;
        let mut fmt = dev
            .format()
            .map_err(|e| device_error(&path, "read format", e))?;
        fmt.width = cfg.width;
        fmt.height = cfg.height;
        fmt.fourcc = FourCC::new(
            fourcc_text(cfg.format)
                .as_bytes()
                .try_into()
                .expect("4-byte fourcc"),
        );
        let fmt = dev
            .set_format(&fmt)
            .map_err(|e| device_error(&path, "set format", e))?;
        let params = dev
            .set_params(&v4l::video::capture::Parameters::with_fps(
                cfg.fps.round() as u32
            ))
            .map_err(|e| device_error(&path, "set frame rate", e))?;
        let fps = (params.interval.numerator > 0)
            .then(|| params.interval.denominator as f64 / params.interval.numerator as f64);
        let granted = Granted {
            width: fmt.width,
            height: fmt.height,
            fourcc: fmt.fourcc.str().unwrap_or("????").to_string(),
            stride: fmt.stride,
            fps,
        };
        let (pixel, warnings) = check_granted(&path, cfg, &granted)?;
        for w in warnings {
            log::warn!("{}: {w}", path.display());
        }
        set_exposure(&dev, &path, cfg);
        let mut stream = Stream::with_buffers(&dev, Type::VideoCapture, cfg.buffers)
            .map_err(|e| device_error(&path, "start streaming", e))?;
        stream.set_timeout(std::time::Duration::from_millis(DEQUEUE_TIMEOUT_MS));
        log::info!(
            "{}: streaming {}x{} {} at {} fps",
            path.display(),
            granted.width,
            granted.height,
            granted.fourcc,
            granted.fps.map_or("?".into(), |f| format!("{f:.2}"))
        );
        Ok(V4lSource {
            path,
            stream,
            granted,
            pixel,
            decoded: Mat::default(),
        })
    }
}

/// Applies the exposure settings; a camera without these controls gets a warning, not an error.
fn set_exposure(dev: &Device, path: &Path, cfg: &V4lConfig) {
    let controls = if cfg.auto_exposure {
        vec![Control {
            id: CID_EXPOSURE_AUTO,
            value: Value::Integer(EXPOSURE_APERTURE_PRIORITY),
        }]
    } else {
        vec![
            Control {
                id: CID_EXPOSURE_AUTO,
                value: Value::Integer(EXPOSURE_MANUAL),
            },
            Control {
                id: CID_EXPOSURE_ABSOLUTE,
                value: Value::Integer(i64::from((cfg.exposure_us / EXPOSURE_UNIT_US).max(1))),
            },
        ]
    };
    for c in controls {
        let id = c.id;
        if let Err(e) = dev.set_control(c) {
            log::warn!(
                "{}: exposure control {id:#x} not applied: {e}",
                path.display()
            );
        }
    }
}

impl FrameSource for V4lSource {
    fn kind(&self) -> FrameSourceKind {
        FrameSourceKind::Camera
    }
    fn describe(&self) -> String {
        format!(
            "v4l {} {}x{} {}",
            self.path.display(),
            self.granted.width,
            self.granted.height,
            self.granted.fourcc
        )
    }
    fn max_frame_len(&self) -> usize {
        let pixels = self.granted.width as usize * self.granted.height as usize;
        match self.pixel {
            Pixel::Yuyv => pixels * 3,
            // BGR, then the camera's JPEG (about a tenth of that; a byte per pixel is ample,
            // and the shared memory grows for a larger one).
            Pixel::Mjpg => pixels * 4,
        }
    }
    fn self_paced(&self) -> bool {
        true
    }
    fn next_frame(&mut self, sink: &mut dyn FrameSink) -> Result<Step, CaptureError> {
        let (buf, meta) = self
            .stream
            .next()
            .map_err(|e| device_error(&self.path, "dequeue frame", e))?;
        let capture_ns = monotonic_ns();
        let used = (meta.bytesused as usize).min(buf.len());
        let data = &buf[..used];
        let seq = meta.sequence as u64;
        let (w, h, stride) = (
            self.granted.width,
            self.granted.height,
            self.granted.stride as usize,
        );
        match self.pixel {
            Pixel::Yuyv => {
                let info = FrameInfo {
                    width: w,
                    height: h,
                    format: PixelFormat::Bgr8,
                    capture_ns: Some(capture_ns),
                    truth: FrameTruth::default(),
                };
                sink.publish(info, &mut |out| {
                    yuyv_to_bgr(data, w as usize, h as usize, stride, out).map(|_| None)
                })?;
            }
            Pixel::Mjpg => {
                let encoded = Vector::<u8>::from_slice(data);
                self.decoded = imgcodecs::imdecode(&encoded, imgcodecs::IMREAD_COLOR)?;
                if opencv::core::MatTraitConst::empty(&self.decoded) {
                    return Err(CaptureError::BadFrame {
                        seq,
                        reason: "MJPG frame does not decode".into(),
                    });
                }
                let m = &self.decoded;
                let info = FrameInfo {
                    width: opencv::core::MatTraitConst::cols(m) as u32,
                    height: opencv::core::MatTraitConst::rows(m) as u32,
                    format: PixelFormat::Bgr8,
                    capture_ns: Some(capture_ns),
                    truth: FrameTruth::default(),
                };
                let fill = &mut |out: &mut [u8]| crate::convert::mat_to_bgr(m, out).map(|_| None);
                if crate::camera_jpeg::recordable_as_is(data) {
                    // The camera's own JPEG goes with the frame: the recorder stores it as it is.
                    sink.publish_with_camera_jpeg(info, data, fill)?;
                } else {
                    sink.publish(info, fill)?;
                }
            }
        }
        Ok(Step::Frame)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn granted(fourcc: &str, w: u32, h: u32, fps: Option<f64>) -> Granted {
        Granted {
            width: w,
            height: h,
            fourcc: fourcc.into(),
            stride: w * 2,
            fps,
        }
    }

    #[test]
    fn exact_grant_has_no_warnings() {
        let req = V4lConfig::default();
        let (pixel, w) = check_granted(
            Path::new("/dev/video0"),
            &req,
            &granted("MJPG", 1280, 720, Some(30.0)),
        )
        .unwrap();
        assert_eq!(pixel, Pixel::Mjpg);
        assert!(w.is_empty(), "{w:?}");
    }

    #[test]
    fn different_size_format_and_rate_are_reported() {
        let req = V4lConfig::default();
        let (pixel, w) = check_granted(
            Path::new("/dev/video0"),
            &req,
            &granted("YUYV", 640, 480, Some(15.0)),
        )
        .unwrap();
        assert_eq!(pixel, Pixel::Yuyv);
        assert_eq!(w.len(), 3, "{w:?}");
        assert!(w.iter().any(|m| m.contains("640x480")));
        assert!(w.iter().any(|m| m.contains("15.00 fps")));
    }

    #[test]
    fn unconvertible_format_is_an_error() {
        let req = V4lConfig::default();
        let err = check_granted(
            Path::new("/dev/video3"),
            &req,
            &granted("NV12", 1280, 720, None),
        )
        .unwrap_err();
        assert!(
            err.to_string().contains("NV12") && err.to_string().contains("/dev/video3"),
            "{err}"
        );
    }

    #[test]
    fn missing_device_is_named() {
        let cfg = V4lConfig {
            device: "/dev/video-does-not-exist".into(),
            ..V4lConfig::default()
        };
        let err = V4lSource::open(&cfg).err().expect("must fail");
        assert!(matches!(err, CaptureError::DeviceNotFound { .. }));
        assert!(
            err.to_string().contains("/dev/video-does-not-exist"),
            "{err}"
        );
    }

    #[test]
    fn os_errors_map_to_clear_errors() {
        let p = Path::new("/dev/video0");
        assert!(matches!(
            device_error(p, "open", io::Error::from_raw_os_error(16)),
            CaptureError::DeviceBusy { .. }
        ));
        assert!(matches!(
            device_error(p, "open", io::Error::from_raw_os_error(2)),
            CaptureError::DeviceNotFound { .. }
        ));
    }
}
