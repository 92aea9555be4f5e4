//! Overlay drawing for debugging dumps (written only where the user asks).
#![allow(dead_code)]

use hubtrack_detect::{LineKind, Output};
use opencv::core::{Mat, Point, Scalar};
use opencv::imgproc;
use opencv::prelude::*;

/// Draw the overlay and truth marks on a copy of a BGR buffer and write it to `path`.
pub fn dump(path: &str, w: u32, h: u32, bgr: &[u8], out: &Output, truth: &[[f64; 2]]) -> opencv::Result<()> {
    let flat = Mat::new_rows_cols_with_data::<u8>(h as i32, (w * 3) as i32, bgr)?;
    let m = flat.reshape(3, h as i32)?;
    let mut img = m.try_clone()?;
    let p = |q: [f64; 2]| Point::new(q[0].round() as i32, q[1].round() as i32);
    for l in &out.overlay.lines {
        let c = match l.kind {
            LineKind::Other => Scalar::new(128.0, 128.0, 128.0, 0.0),
            LineKind::Tower => Scalar::new(0.0, 0.0, 255.0, 0.0),
            LineKind::Blade => Scalar::new(0.0, 255.0, 0.0, 0.0),
            LineKind::Rejected => Scalar::new(255.0, 0.0, 255.0, 0.0),
        };
        imgproc::line(&mut img, p(l.a), p(l.b), c, 3, imgproc::LINE_8, 0)?;
    }
    if let Some(c) = out.overlay.search_circle {
        imgproc::circle(&mut img, p([c[0], c[1]]), c[2] as i32, Scalar::new(0.0, 255.0, 255.0, 0.0), 2, imgproc::LINE_8, 0)?;
    }
    for t in truth {
        imgproc::circle(&mut img, p(*t), 10, Scalar::new(255.0, 255.0, 0.0, 0.0), 3, imgproc::LINE_8, 0)?;
    }
    let d = &out.detection;
    if d.detected {
        imgproc::circle(&mut img, p(d.hub_px), 18, Scalar::new(0.0, 0.0, 255.0, 0.0), 4, imgproc::LINE_8, 0)?;
    }
    if d.tower_found {
        imgproc::circle(&mut img, p(d.tower_top_px), 8, Scalar::new(255.0, 0.0, 0.0, 0.0), -1, imgproc::LINE_8, 0)?;
    }
    let mut small = Mat::default();
    imgproc::resize(&img, &mut small, opencv::core::Size::new(960, 540), 0.0, 0.0, imgproc::INTER_AREA)?;
    opencv::imgcodecs::imwrite_def(path, &small)?;
    Ok(())
}
