//! Video-file source through OpenCV videoio.

use crate::convert::mat_to_bgr;
use crate::{CaptureError, FrameInfo, FrameSink, FrameSource, Step};
use hubtrack_types::time::monotonic_ns;
use hubtrack_types::{FrameSourceKind, FrameTruth, PixelFormat};
use opencv::core::{Mat, MatTraitConst};
use opencv::prelude::{VideoCaptureTrait, VideoCaptureTraitConst};
use opencv::videoio::{self, VideoCapture};
use std::path::{Path, PathBuf};

/// Frames of a video file, looped or once.
pub struct VideoSource {
    path: PathBuf,
    cap: VideoCapture,
    looping: bool,
    fps: Option<f64>,
    size: (u32, u32),
    frame: Mat,
}

impl VideoSource {
    /// Opens `path`; a missing or undecodable file is a clear error.
    pub fn open(path: &Path, looping: bool) -> Result<VideoSource, CaptureError> {
        if path.as_os_str().is_empty() || !path.is_file() {
            return Err(CaptureError::VideoNotFound { path: path.into() });
        }
        let unreadable = || CaptureError::VideoUnreadable { path: path.into() };
        let name = path.to_str().ok_or_else(unreadable)?;
        let mut cap = VideoCapture::from_file(name, videoio::CAP_ANY)?;
        if !cap.is_opened()? {
            return Err(unreadable());
        }
        // Read one frame now so a file that opens but does not decode fails at start.
        let mut frame = Mat::default();
        if !cap.read(&mut frame)? || frame.empty() {
            return Err(unreadable());
        }
        cap.set(videoio::CAP_PROP_POS_FRAMES, 0.0)?;
        let fps = cap.get(videoio::CAP_PROP_FPS)?;
        Ok(VideoSource {
            path: path.into(),
            looping,
            fps: (fps.is_finite() && fps > 0.0).then_some(fps),
            size: (frame.cols() as u32, frame.rows() as u32),
            cap,
            frame,
        })
    }
}

impl FrameSource for VideoSource {
    fn kind(&self) -> FrameSourceKind {
        FrameSourceKind::Video
    }
    fn describe(&self) -> String {
        format!(
            "video {} {}x{} at {} fps{}",
            self.path.display(),
            self.size.0,
            self.size.1,
            self.fps.map_or("?".into(), |f| format!("{f:.2}")),
            if self.looping { ", looped" } else { "" }
        )
    }
    fn max_frame_len(&self) -> usize {
        self.size.0 as usize * self.size.1 as usize * 3
    }
    fn self_paced(&self) -> bool {
        false
    }
    fn native_fps(&self) -> Option<f64> {
        self.fps
    }
    fn next_frame(&mut self, sink: &mut dyn FrameSink) -> Result<Step, CaptureError> {
        if !self.cap.read(&mut self.frame)? || self.frame.empty() {
            if !self.looping {
                return Ok(Step::End);
            }
            self.cap.set(videoio::CAP_PROP_POS_FRAMES, 0.0)?;
            if !self.cap.read(&mut self.frame)? || self.frame.empty() {
                return Err(CaptureError::VideoUnreadable {
                    path: self.path.clone(),
                });
            }
        }
        let m = &self.frame;
        let info = FrameInfo {
            width: m.cols() as u32,
            height: m.rows() as u32,
            format: PixelFormat::Bgr8,
            capture_ns: Some(monotonic_ns()),
            truth: FrameTruth::default(),
        };
        sink.publish(info, &mut |out| mat_to_bgr(m, out).map(|_| None))?;
        Ok(Step::Frame)
    }
}
