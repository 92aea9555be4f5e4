//! The capture stage: frame sources behind one trait, published zero-copy on the frames service.
//!
//! A [`FrameSource`] produces frames and hands each one to a [`FrameSink`]; the sink decides where
//! the pixels go (shared memory in the process, a `Vec` in tests) and the source writes them
//! straight there: the synthetic renderer renders into the loaned sample, the YUYV converter
//! converts into it. Sources: [`v4l_source`] (camera), [`video`] (file), [`images`] (stills),
//! [`synthetic`] (renderer).

#![warn(missing_docs)]

pub mod camera_jpeg;
pub mod config;
pub mod convert;
pub mod image_header;
pub mod images;
pub mod pacing;
pub mod sink;
pub mod synthetic;
pub mod v4l_source;
pub mod video;

use config::{CaptureConfig, SourceKind};
use hubtrack_types::{FrameSourceKind, FrameTruth, PixelFormat};
use std::path::PathBuf;

/// Why capture failed.
#[derive(Debug, thiserror::Error)]
pub enum CaptureError {
    /// The V4L2 device path does not exist.
    #[error("camera device {path} does not exist (is the camera plugged in? `ls /dev/video*` lists devices)")]
    DeviceNotFound {
        /// Device path.
        path: PathBuf,
    },
    /// Another process holds the device.
    #[error("camera device {path} is busy (another process is streaming from it; `fuser {path}` shows which)")]
    DeviceBusy {
        /// Device path.
        path: PathBuf,
    },
    /// The device refused an operation.
    #[error("camera device {path}: {what}: {reason}")]
    Device {
        /// Device path.
        path: PathBuf,
        /// What was attempted.
        what: &'static str,
        /// The driver's answer.
        reason: String,
    },
    /// The driver granted a pixel format hubtrack cannot convert.
    #[error("camera device {path} granted pixel format {fourcc}, which hubtrack cannot convert (use MJPG or YUYV)")]
    UnsupportedFormat {
        /// Device path.
        path: PathBuf,
        /// The granted FourCC.
        fourcc: String,
    },
    /// A camera frame could not be decoded.
    #[error("camera frame {seq} could not be decoded: {reason}")]
    BadFrame {
        /// Driver sequence number.
        seq: u64,
        /// Why.
        reason: String,
    },
    /// The video file does not exist.
    #[error("video file {path} does not exist")]
    VideoNotFound {
        /// File path.
        path: PathBuf,
    },
    /// The video file exists but OpenCV cannot read it.
    #[error("video file {path} cannot be opened or decoded (unsupported container/codec or corrupt file)")]
    VideoUnreadable {
        /// File path.
        path: PathBuf,
    },
    /// No image matched the configured path.
    #[error(
        "no image found at `{pattern}` (a folder of .jpg/.jpeg/.png/.bmp/.tif, a file, or a glob)"
    )]
    ImagesNotFound {
        /// The configured path.
        pattern: String,
    },
    /// An image file could not be decoded.
    #[error("image {path} cannot be read (not an image, corrupt, or unsupported format)")]
    ImageUnreadable {
        /// File path.
        path: PathBuf,
    },
    /// A JPEG ends before its end-of-image marker (a cut transfer, a full card): the decoder
    /// would fill the missing rows with grey.
    #[error("image {path} is cut short: the JPEG ends before its end-of-image marker")]
    ImageTruncated {
        /// File path.
        path: PathBuf,
    },
    /// An image declares more pixels than [`image_header::MAX_IMAGE_PIXELS`] (refused before
    /// decoding: a small file can declare gigabytes of pixels).
    #[error("image {path} declares {width}x{height} pixels, more than the {limit} allowed: refused before decoding")]
    ImageTooLarge {
        /// File path.
        path: PathBuf,
        /// Declared width, px.
        width: u32,
        /// Declared height, px.
        height: u32,
        /// The limit, pixels.
        limit: u64,
    },
    /// Every image of the set was unreadable.
    #[error("none of the {count} images at `{pattern}` could be read")]
    NoReadableImage {
        /// The configured path.
        pattern: String,
        /// How many files were tried.
        count: usize,
    },
    /// The output buffer has the wrong size for the frame.
    #[error("frame buffer has {got} bytes, frame needs {expected}")]
    BufferSize {
        /// Needed.
        expected: usize,
        /// Given.
        got: usize,
    },
    /// The renderer failed.
    #[error("synthetic renderer: {0}")]
    Render(String),
    /// An image file could not be written.
    #[error("cannot write {path}: {reason}")]
    ImageWrite {
        /// The file.
        path: PathBuf,
        /// Why, as far as it is known.
        reason: String,
    },
    /// OpenCV failed.
    #[error("OpenCV: {0}")]
    OpenCv(#[from] opencv::Error),
    /// Shared memory failed.
    #[error(transparent)]
    Ipc(#[from] hubtrack_runtime::ipc::IpcError),
}

impl CaptureError {
    /// A per-frame problem after which the source can go on with the next frame.
    pub fn is_per_frame(&self) -> bool {
        matches!(
            self,
            CaptureError::ImageUnreadable { .. }
                | CaptureError::ImageTruncated { .. }
                | CaptureError::ImageTooLarge { .. }
                | CaptureError::BadFrame { .. }
        )
    }
}

/// What a source tells the sink about one frame before its pixels are written.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FrameInfo {
    /// Width, px.
    pub width: u32,
    /// Height, px.
    pub height: u32,
    /// Pixel layout (sources always produce [`PixelFormat::Bgr8`] today).
    pub format: PixelFormat,
    /// Monotonic ns when the frame was exposed or dequeued; `None`: when its pixels are ready
    /// (rendered frames: the renderer stands in for the sensor, so rendering is not latency).
    pub capture_ns: Option<u64>,
    /// Exact truth for rendered frames.
    pub truth: FrameTruth,
}

impl FrameInfo {
    /// Bytes per row of a tightly packed frame.
    pub fn stride(&self) -> usize {
        self.width as usize * self.format.bytes_per_pixel()
    }
    /// Bytes of a tightly packed frame.
    pub fn len(&self) -> usize {
        self.stride() * self.height as usize
    }
    /// True for an empty frame.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// Pixel writer handed to a sink: writes the frame's pixels into the given buffer and returns
/// the frame's truth when it is only known after writing (rendered frames), else `None`.
pub type Fill<'a> = dyn FnMut(&mut [u8]) -> Result<Option<FrameTruth>, CaptureError> + 'a;

/// Where frames go.
pub trait FrameSink {
    /// Takes one frame: provides a buffer of `info.len()` bytes and calls `fill` on it.
    fn publish(&mut self, info: FrameInfo, fill: &mut Fill<'_>) -> Result<(), CaptureError>;

    /// Takes one frame the camera also delivered as a JPEG (`jpeg`, of the same size as the
    /// pixels): a sink that can keeps those bytes with the frame, so the recorder stores the
    /// camera's own JPEG instead of encoding the pixels again. By default only the pixels.
    fn publish_with_camera_jpeg(
        &mut self,
        info: FrameInfo,
        jpeg: &[u8],
        fill: &mut Fill<'_>,
    ) -> Result<(), CaptureError> {
        let _ = jpeg;
        self.publish(info, fill)
    }
}

/// What one call of [`FrameSource::next_frame`] did.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Step {
    /// A frame went to the sink.
    Frame,
    /// The source has no more frames.
    End,
}

/// A source of frames.
pub trait FrameSource {
    /// Which kind of source this is (stamped into each frame header).
    fn kind(&self) -> FrameSourceKind;
    /// One line saying what is being captured, for the log.
    fn describe(&self) -> String;
    /// Largest frame in bytes this source expects to produce (sizes the shared memory).
    fn max_frame_len(&self) -> usize;
    /// True when the source paces itself (a camera); false when capture must pace it.
    fn self_paced(&self) -> bool;
    /// The source's own frame rate, if it has one (video files).
    fn native_fps(&self) -> Option<f64> {
        None
    }
    /// Produces the next frame into `sink` (blocking until a camera delivers one).
    fn next_frame(&mut self, sink: &mut dyn FrameSink) -> Result<Step, CaptureError>;
}

/// Opens the source selected by `config.source`, with a clear error when it cannot be used.
pub fn open_source(
    config: &CaptureConfig,
    filming: &synthetic::Filming,
) -> Result<Box<dyn FrameSource>, CaptureError> {
    Ok(match config.source {
        SourceKind::V4l => Box::new(v4l_source::V4lSource::open(&config.v4l)?),
        SourceKind::Video => Box::new(video::VideoSource::open(
            &config.video.path,
            config.looping,
        )?),
        SourceKind::Images => Box::new(images::ImageSource::open(
            &config.images.path,
            config.looping,
        )?),
        SourceKind::Synthetic => Box::new(
            synthetic::SyntheticSource::new(&config.synthetic, config.fps)?.filming(filming),
        ),
    })
}

/// Checks that a sink buffer fits the frame.
pub(crate) fn check_len(buf: &[u8], expected: usize) -> Result<(), CaptureError> {
    if buf.len() == expected {
        Ok(())
    } else {
        Err(CaptureError::BufferSize {
            expected,
            got: buf.len(),
        })
    }
}
