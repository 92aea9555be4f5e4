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

fn is_jpeg_name(p: &Path) -> bool {
    p.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("jpg") || e.eq_ignore_ascii_case("jpeg"))
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

/// How far from its end a JPEG's end-of-image marker is looked for: some cameras write a few
/// bytes of padding or trailer after it.
const JPEG_END_SEARCH: usize = 1024;

/// Whether `head` (the first bytes) and `tail` (the last [`JPEG_END_SEARCH`] bytes) are those of
/// a JPEG cut before its end-of-image marker (FF D9). Inside a JPEG's entropy-coded data an FF
/// byte is always followed by 00 or a restart marker, so FF D9 near the end is the marker.
/// A tail of zeros only (padding longer than the search) says nothing: not taken for a cut.
fn jpeg_cut_short(head: &[u8], tail: &[u8]) -> bool {
    let end = tail.iter().rposition(|&b| b != 0).map_or(0, |i| i + 1);
    head.starts_with(&[0xFF, 0xD8]) && end > 0 && !tail[..end].windows(2).any(|w| w == [0xFF, 0xD9])
}

/// Refuses a JPEG file cut before its end (see [`jpeg_cut_short`]); other files pass.
fn check_jpeg_end(path: &Path) -> Result<(), CaptureError> {
    use std::io::{Read, Seek, SeekFrom};
    let read = || -> std::io::Result<bool> {
        let mut f = std::fs::File::open(path)?;
        let mut head = [0u8; 2];
        let n = f.read(&mut head)?;
        let len = f.seek(SeekFrom::End(0))?;
        f.seek(SeekFrom::Start(len.saturating_sub(JPEG_END_SEARCH as u64)))?;
        let mut tail = Vec::with_capacity(JPEG_END_SEARCH);
        f.read_to_end(&mut tail)?;
        Ok(jpeg_cut_short(&head[..n], &tail))
    };
    match read() {
        Ok(true) => Err(CaptureError::ImageTruncated { path: path.into() }),
        Ok(false) => Ok(()),
        Err(_) => Err(CaptureError::ImageUnreadable { path: path.into() }),
    }
}

/// Reads one image as BGR8; an unreadable file is [`CaptureError::ImageUnreadable`], a JPEG
/// cut short [`CaptureError::ImageTruncated`].
pub fn read_image(path: &Path) -> Result<opencv::core::Mat, CaptureError> {
    let unreadable = || CaptureError::ImageUnreadable { path: path.into() };
    let name = path.to_str().ok_or_else(unreadable)?;
    check_declared(
        path,
        crate::image_header::declared_size(path).map_err(|_| unreadable())?,
    )?;
    check_jpeg_end(path)?;
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
    if jpeg_cut_short(bytes, &bytes[bytes.len().saturating_sub(JPEG_END_SEARCH)..]) {
        return Err(CaptureError::ImageTruncated { path: name.into() });
    }
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
        // A JPEG file is read once: decoded for the pixels, and its bytes go with the frame
        // when they show exactly those pixels (the recorder then stores the file's JPEG).
        let jpeg = is_jpeg_name(path)
            .then(|| std::fs::read(path).ok())
            .flatten()
            .filter(|b| crate::camera_jpeg::recordable_as_is(b));
        let m = match &jpeg {
            Some(bytes) => decode_image(bytes, path)?,
            None => read_image(path)?,
        };
        self.readable_this_pass += 1;
        let info = FrameInfo {
            width: m.cols() as u32,
            height: m.rows() as u32,
            format: PixelFormat::Bgr8,
            capture_ns: Some(monotonic_ns()),
            truth: FrameTruth::default(),
        };
        let fill = &mut |out: &mut [u8]| mat_to_bgr(&m, out).map(|_| None);
        match &jpeg {
            Some(bytes) => sink.publish_with_camera_jpeg(info, bytes, fill)?,
            None => sink.publish(info, fill)?,
        }
        Ok(Step::Frame)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sink::VecSink;

    fn write_image(path: &Path) {
        let m = opencv::core::Mat::new_rows_cols_with_default(
            40,
            60,
            opencv::core::CV_8UC3,
            opencv::core::Scalar::new(30.0, 120.0, 200.0, 0.0),
        )
        .unwrap();
        imgcodecs::imwrite_def(path.to_str().unwrap(), &m).unwrap();
    }

    #[test]
    fn a_jpeg_files_bytes_go_with_its_frame_and_a_pngs_do_not() {
        let dir = tempfile::tempdir().unwrap();
        let (jpg, png) = (dir.path().join("a.jpg"), dir.path().join("b.png"));
        write_image(&jpg);
        write_image(&png);
        let mut src = ImageSource::open(dir.path().to_str().unwrap(), false).unwrap();
        let mut sink = VecSink::default();

        assert_eq!(src.next_frame(&mut sink).unwrap(), Step::Frame);
        assert_eq!(sink.camera_jpeg, std::fs::read(&jpg).unwrap());
        assert_eq!(sink.header.camera_jpeg_len as usize, sink.camera_jpeg.len());
        assert_eq!((sink.header.width, sink.header.height), (60, 40));
        assert_eq!(
            sink.pixels.len(),
            60 * 40 * 3,
            "the pixels are decoded all the same"
        );

        assert_eq!(src.next_frame(&mut sink).unwrap(), Step::Frame);
        assert!(sink.camera_jpeg.is_empty());
        assert_eq!(sink.header.camera_jpeg_len, 0);
    }

    #[test]
    fn a_jpeg_cut_before_its_end_is_refused_and_a_whole_one_read() {
        let dir = tempfile::tempdir().unwrap();
        let (whole, cut) = (dir.path().join("whole.jpg"), dir.path().join("cut.jpg"));
        write_image(&whole);
        let bytes = std::fs::read(&whole).unwrap();
        std::fs::write(&cut, &bytes[..bytes.len() * 2 / 3]).unwrap();
        assert!(read_image(&whole).is_ok());
        assert!(matches!(
            read_image(&cut),
            Err(CaptureError::ImageTruncated { .. })
        ));
        assert!(matches!(
            decode_image(&bytes[..bytes.len() - 2], &cut),
            Err(CaptureError::ImageTruncated { .. })
        ));
        // A few bytes after the marker (a camera's padding) are no cut.
        let mut padded = bytes.clone();
        padded.extend_from_slice(&[0; 16]);
        assert!(decode_image(&padded, &whole).is_ok());
    }
}
