//! Still-image source: a folder (name order), one file, or a glob.

use crate::convert::mat_to_bgr;
use crate::{CaptureError, FrameInfo, FrameSink, FrameSource, Step};
use hubtrack_types::time::monotonic_ns;
use hubtrack_types::{FrameSourceKind, FrameTruth, PixelFormat};
use opencv::core::MatTraitConst;
use opencv::imgcodecs;
use std::path::{Path, PathBuf};

/// File extensions taken from a folder (case-insensitive).
pub const IMAGE_EXTENSIONS: &[&str] = &["jpg", "jpeg", "png", "bmp", "tif", "tiff", "webp"];

/// Lists the images named by `pattern`: a folder's images in file-name order, a single file, or
/// the matches of a glob in name order.
pub fn list_images(pattern: &str) -> Result<Vec<PathBuf>, CaptureError> {
    let not_found = || CaptureError::ImagesNotFound {
        pattern: pattern.into(),
    };
    if pattern.is_empty() {
        return Err(not_found());
    }
    let path = Path::new(pattern);
    let mut files: Vec<PathBuf> = if path.is_dir() {
        std::fs::read_dir(path)
            .map_err(|_| not_found())?
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.is_file() && has_image_extension(p))
            .collect()
    } else if path.is_file() {
        vec![path.to_path_buf()]
    } else {
        glob::glob(pattern)
            .map_err(|_| not_found())?
            .filter_map(Result::ok)
            .filter(|p| p.is_file())
            .collect()
    };
    files.sort();
    if files.is_empty() {
        return Err(not_found());
    }
    Ok(files)
}

/// True when the file name ends in one of [`IMAGE_EXTENSIONS`].
pub fn has_image_extension(p: &Path) -> bool {
    p.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| IMAGE_EXTENSIONS.contains(&e.to_ascii_lowercase().as_str()))
}

/// Refuses a declared size over [`crate::image_header::MAX_IMAGE_PIXELS`] before decoding.
fn check_declared(path: &Path, declared: Option<(u32, u32)>) -> Result<(), CaptureError> {
    if let Some((width, height)) = declared {
        let limit = crate::image_header::MAX_IMAGE_PIXELS;
        if u64::from(width) * u64::from(height) > limit {
            return Err(CaptureError::ImageTooLarge {
                path: path.into(),
                width,
                height,
                limit,
            });
        }
    }
    Ok(())
}

/// Reads one image as BGR8; an unreadable file is [`CaptureError::ImageUnreadable`].
pub fn read_image(path: &Path) -> Result<opencv::core::Mat, CaptureError> {
    let unreadable = || CaptureError::ImageUnreadable { path: path.into() };
    let name = path.to_str().ok_or_else(unreadable)?;
    check_declared(
        path,
        crate::image_header::declared_size(path).map_err(|_| unreadable())?,
    )?;
    let m = imgcodecs::imread(name, imgcodecs::IMREAD_COLOR).map_err(|_| unreadable())?;
    if m.empty() {
        return Err(unreadable());
    }
    Ok(m)
}

/// Decodes an encoded image (PNG, JPEG, BMP, ...) held in memory as BGR8, with the same pixel
/// limit as [`read_image`]; `name` names it in errors.
pub fn decode_image(bytes: &[u8], name: &Path) -> Result<opencv::core::Mat, CaptureError> {
    let unreadable = || CaptureError::ImageUnreadable { path: name.into() };
    check_declared(name, crate::image_header::size_from_bytes(bytes))?;
    let buf = opencv::core::Vector::<u8>::from_slice(bytes);
    let m = imgcodecs::imdecode(&buf, imgcodecs::IMREAD_COLOR).map_err(|_| unreadable())?;
    if m.empty() {
        return Err(unreadable());
    }
    Ok(m)
}

/// Still images, looped or once. An unreadable image is reported and skipped; if a whole pass
/// yields no readable image the source fails.
pub struct ImageSource {
    pattern: String,
    files: Vec<PathBuf>,
    next: usize,
    looping: bool,
    readable_this_pass: usize,
    max_len: usize,
}

impl ImageSource {
    /// Lists the images and reads the first one to size the shared memory.
    pub fn open(pattern: &str, looping: bool) -> Result<ImageSource, CaptureError> {
        let files = list_images(pattern)?;
        // Size shared memory from the first readable image (others may be larger: it grows).
        let max_len = files
            .iter()
            .find_map(|f| read_image(f).ok())
            .map(|m| m.cols() as usize * m.rows() as usize * 3)
            .ok_or_else(|| {
                if files.len() == 1 {
                    CaptureError::ImageUnreadable {
                        path: files[0].clone(),
                    }
                } else {
                    CaptureError::NoReadableImage {
                        pattern: pattern.into(),
                        count: files.len(),
                    }
                }
            })?;
        Ok(ImageSource {
            pattern: pattern.into(),
            files,
            next: 0,
            looping,
            readable_this_pass: 0,
            max_len,
        })
    }
}

impl FrameSource for ImageSource {
    fn kind(&self) -> FrameSourceKind {
        FrameSourceKind::Images
    }
    fn describe(&self) -> String {
        format!(
            "images `{}` ({} files{})",
            self.pattern,
            self.files.len(),
            if self.looping { ", looped" } else { "" }
        )
    }
    fn max_frame_len(&self) -> usize {
        self.max_len
    }
    fn self_paced(&self) -> bool {
        false
    }
    fn next_frame(&mut self, sink: &mut dyn FrameSink) -> Result<Step, CaptureError> {
        if self.next == self.files.len() {
            if !self.looping {
                return Ok(Step::End);
            }
            if self.readable_this_pass == 0 {
                return Err(CaptureError::NoReadableImage {
                    pattern: self.pattern.clone(),
                    count: self.files.len(),
                });
            }
            self.next = 0;
            self.readable_this_pass = 0;
        }
        let path = &self.files[self.next];
        self.next += 1;
        let m = read_image(path)?;
        self.readable_this_pass += 1;
        let info = FrameInfo {
            width: m.cols() as u32,
            height: m.rows() as u32,
            format: PixelFormat::Bgr8,
            capture_ns: Some(monotonic_ns()),
            truth: FrameTruth::default(),
        };
        sink.publish(info, &mut |out| mat_to_bgr(&m, out).map(|_| None))?;
        Ok(Step::Frame)
    }
}
