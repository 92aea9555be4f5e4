//! The `detect` target of `hubtrack fuzz`: adversarial images through the image loader and
//! adversarial hints through the detector.
//!
//! An input is a hint header followed by an encoded image file:
//!
//! ```text
//! byte 0      flags: bit 0 roll given, bit 1 predicted hub given, bit 2 distance given
//! bytes 1..9  roll, radians (f64, little endian)
//! bytes 9..25 predicted hub x, y, px (2 × f64)
//! bytes 25..33 hub distance, m (f64)
//! bytes 33..  the image file (PNG, JPEG, BMP, ...), decoded as `hubtrack detect` reads photos
//! ```
//!
//! Mutations of the header give NaN, infinities, huge and negative values and hubs far off the
//! frame; mutations of the image give damaged headers, truncated data and odd sizes. The seeds in
//! `tests/fuzz-corpus/detect/` are small generated images (`write_corpus` in the tests makes
//! them).

use hubtrack_detect::{Detector, Hints};
use std::path::Path;

/// Length of the hint header before the image bytes.
pub const HEADER_LEN: usize = 33;
/// Images up to this many pixels also go through the still-photo path (`detect_still`, about 8×
/// the work: finer pyramid level and the mirror image).
const STILL_MAX_PIXELS: i32 = 320 * 240;

fn f64_at(b: &[u8], i: usize) -> f64 {
    f64::from_le_bytes(b[i..i + 8].try_into().expect("8 bytes"))
}

/// The hints of an input's header (`None` when the input is shorter than the header).
pub fn hints(input: &[u8]) -> Option<Hints> {
    let h = input.get(..HEADER_LEN)?;
    let flag = |bit: u8| h[0] & (1 << bit) != 0;
    Some(Hints {
        roll_rad: flag(0).then(|| f64_at(h, 1)),
        predicted_hub_px: flag(1).then(|| [f64_at(h, 9), f64_at(h, 17)]),
        hub_distance_m: flag(2).then(|| f64_at(h, 25)),
    })
}

/// An input from hints and image bytes.
#[cfg(test)]
fn input(hints: &Hints, image: &[u8]) -> Vec<u8> {
    let mut b = vec![0u8; HEADER_LEN];
    if let Some(r) = hints.roll_rad {
        b[0] |= 1;
        b[1..9].copy_from_slice(&r.to_le_bytes());
    }
    if let Some([x, y]) = hints.predicted_hub_px {
        b[0] |= 2;
        b[9..17].copy_from_slice(&x.to_le_bytes());
        b[17..25].copy_from_slice(&y.to_le_bytes());
    }
    if let Some(d) = hints.hub_distance_m {
        b[0] |= 4;
        b[25..33].copy_from_slice(&d.to_le_bytes());
    }
    b.extend_from_slice(image);
    b
}

/// Runs one input: decode the image (errors are fine), detect on it with the hints as the detect
/// stage does, and small images also as a still photo. Only a panic is a failure.
pub fn run(det: &mut Detector, input: &[u8]) {
    let Some(h) = hints(input) else {
        return;
    };
    let Ok(mat) = hubtrack_capture::images::decode_image(&input[HEADER_LEN..], Path::new("mutant"))
    else {
        return;
    };
    let Ok(view) = crate::detect_cmd::view_of(&mat) else {
        return;
    };
    std::hint::black_box(det.detect(&view, &h).ok());
    if opencv::core::MatTraitConst::cols(&mat) * opencv::core::MatTraitConst::rows(&mat)
        <= STILL_MAX_PIXELS
    {
        std::hint::black_box(det.detect_still(&view, &h).ok());
    }
}

/// The detector the target uses: the default configuration. OpenCV's own warnings about
/// undecodable mutants are silenced (each one is an expected error, not news).
pub fn detector() -> Detector {
    let _ = opencv::core::set_log_level(opencv::core::LogLevel::LOG_LEVEL_ERROR);
    Detector::new(hubtrack_detect::params::DetectConfig::default())
        .expect("the default detect configuration is valid")
}

/// Writes the seed corpus into `dir`: small generated images (a few KB each, none a photo),
/// each with its hints. Regenerate with
/// `cargo test --release -p hubtrack-lab write_detect_corpus -- --ignored`.
#[cfg(test)]
fn write_corpus(dir: &Path) -> anyhow::Result<()> {
    use opencv::core::{Mat, Point, Scalar, Vector, CV_8UC3};
    use opencv::imgcodecs::imencode;
    use opencv::imgproc;
    use opencv::prelude::*;

    std::fs::create_dir_all(dir)?;
    let solid = |w: i32, h: i32, v: f64| {
        Mat::new_rows_cols_with_default(h, w, CV_8UC3, Scalar::all(v)).expect("mat")
    };
    let encode = |m: &Mat, ext: &str| -> anyhow::Result<Vec<u8>> {
        let mut buf = Vector::<u8>::new();
        imencode(ext, m, &mut buf, &Vector::new())?;
        Ok(buf.to_vec())
    };
    // A turbine as the detector expects one: sky, a dark tower, three blades from the hub.
    let mut turbine = solid(160, 120, 200.0);
    let hub = Point::new(80, 45);
    let dark = Scalar::all(40.0);
    imgproc::rectangle_points(
        &mut turbine,
        Point::new(77, 45),
        Point::new(83, 119),
        dark,
        -1,
        imgproc::LINE_8,
        0,
    )?;
    for end in [Point::new(80, 0), Point::new(30, 75), Point::new(130, 75)] {
        imgproc::line(&mut turbine, hub, end, dark, 3, imgproc::LINE_AA, 0)?;
    }
    imgproc::circle(&mut turbine, hub, 5, dark, -1, imgproc::LINE_AA, 0)?;
    // Extreme contrast: a hard horizon, and black/white columns.
    let mut horizon = solid(96, 72, 255.0);
    imgproc::rectangle_points(
        &mut horizon,
        Point::new(0, 36),
        Point::new(95, 71),
        Scalar::all(0.0),
        -1,
        imgproc::LINE_8,
        0,
    )?;
    let mut stripes = solid(48, 36, 0.0);
    for x in (0..48).step_by(4) {
        imgproc::rectangle_points(
            &mut stripes,
            Point::new(x, 0),
            Point::new(x + 1, 35),
            Scalar::all(255.0),
            -1,
            imgproc::LINE_8,
            0,
        )?;
    }
    let mut noise = solid(48, 36, 0.0);
    let mut rng = hubtrack_types::mutate::Rng::new(45);
    for b in noise.data_bytes_mut()? {
        *b = rng.next_u64() as u8;
    }
    let none = Hints::default();
    let level = Hints {
        roll_rad: Some(0.02),
        predicted_hub_px: Some([80.0, 45.0]),
        hub_distance_m: Some(30.0),
    };
    let hostile = [
        Hints {
            roll_rad: Some(1.5),
            predicted_hub_px: Some([-1e9, 5.0]),
            hub_distance_m: Some(0.0),
        },
        Hints {
            roll_rad: Some(f64::NAN),
            predicted_hub_px: Some([f64::INFINITY, f64::NEG_INFINITY]),
            hub_distance_m: Some(-5.0),
        },
        Hints {
            roll_rad: Some(-1e300),
            predicted_hub_px: Some([1e18, -1e18]),
            hub_distance_m: Some(f64::MAX),
        },
        Hints {
            roll_rad: Some(std::f64::consts::PI),
            predicted_hub_px: Some([f64::NAN, 0.0]),
            hub_distance_m: Some(f64::MIN_POSITIVE),
        },
    ];
    let turbine_jpg = encode(&turbine, ".jpg")?;
    let turbine_png = encode(&turbine, ".png")?;
    let mut seeds: Vec<(&str, Hints, Vec<u8>)> = vec![
        ("turbine-level.jpg", level, turbine_jpg.clone()),
        (
            "turbine-rolled-offframe.png",
            hostile[0],
            turbine_png.clone(),
        ),
        ("turbine-nan.jpg", hostile[1], turbine_jpg.clone()),
        ("turbine-huge.png", hostile[2], turbine_png),
        (
            "pixel-1x1.png",
            hostile[3],
            encode(&solid(1, 1, 128.0), ".png")?,
        ),
        ("pixel-1x1.jpg", none, encode(&solid(1, 1, 128.0), ".jpg")?),
        ("black.png", level, encode(&solid(64, 48, 0.0), ".png")?),
        (
            "white.jpg",
            hostile[0],
            encode(&solid(64, 48, 255.0), ".jpg")?,
        ),
        ("noise.png", hostile[1], encode(&noise, ".png")?),
        ("horizon.png", level, encode(&horizon, ".png")?),
        ("stripes.bmp", hostile[2], encode(&stripes, ".bmp")?),
        (
            "wide-200x4.png",
            level,
            encode(&solid(200, 4, 90.0), ".png")?,
        ),
        (
            "tall-4x200.jpg",
            hostile[3],
            encode(&solid(4, 200, 90.0), ".jpg")?,
        ),
        // Large but within the pixel limit (3 Mpx; compresses to a few KB).
        (
            "large-2000x1500.png",
            level,
            encode(&solid(2000, 1500, 20.0), ".png")?,
        ),
    ];
    // Damaged headers: a truncated JPEG, a PNG whose header declares a bomb.
    let truncated = turbine_jpg[..turbine_jpg.len() / 3].to_vec();
    seeds.push(("truncated.jpg", level, truncated));
    let mut bomb = encode(&solid(8, 8, 0.0), ".png")?;
    bomb[16..24].copy_from_slice(&[0, 1, 0, 0, 0, 1, 0, 0]); // 65536 x 65536, CRC left stale
    seeds.push(("bomb-header.png", none, bomb));
    for (name, h, image) in seeds {
        std::fs::write(dir.join(format!("{name}.bin")), input(&h, &image))?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use hubtrack_types::mutate::{mutate, Rng};

    fn corpus_dir() -> std::path::PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/fuzz-corpus/detect")
    }

    #[test]
    #[ignore]
    fn write_detect_corpus() {
        write_corpus(&corpus_dir()).unwrap();
    }

    #[test]
    fn header_round_trip() {
        let h = Hints {
            roll_rad: Some(f64::NEG_INFINITY),
            predicted_hub_px: None,
            hub_distance_m: Some(7.5),
        };
        let back = hints(&input(&h, b"img")).unwrap();
        assert_eq!(back.roll_rad, h.roll_rad);
        assert_eq!(back.predicted_hub_px, None);
        assert_eq!(back.hub_distance_m, Some(7.5));
        assert!(hints(&[0; HEADER_LEN - 1]).is_none());
    }

    /// Every seed decodes (except the damaged ones) and detects without a panic, and a seeded
    /// run of mutants of them through the target never panics.
    #[test]
    fn seeded_mutants_never_panic_the_detector() {
        let seeds: Vec<(String, Vec<u8>)> = std::fs::read_dir(corpus_dir())
            .expect("tests/fuzz-corpus/detect")
            .map(|e| {
                let p = e.unwrap().path();
                (p.display().to_string(), std::fs::read(&p).unwrap())
            })
            .collect();
        assert!(seeds.len() >= 10, "{} seeds", seeds.len());
        let mut det = detector();
        for (name, s) in &seeds {
            let decodes = hubtrack_capture::images::decode_image(&s[HEADER_LEN..], Path::new(name));
            // The bomb is refused by its header, a JPEG cut short by its missing end marker.
            let (bomb, cut) = (name.contains("bomb"), name.contains("truncated"));
            assert_eq!(decodes.is_ok(), !bomb && !cut, "{name}");
            if bomb {
                let err = decodes.unwrap_err().to_string();
                assert!(err.contains("65536x65536"), "{err}");
            } else if cut {
                let err = decodes.unwrap_err().to_string();
                assert!(err.contains("cut short"), "{err}");
            }
            run(&mut det, s);
        }
        // Mutants of the small seeds (the large one costs ~100x a small one).
        let small: Vec<&Vec<u8>> = seeds
            .iter()
            .filter(|(n, _)| !n.contains("large"))
            .map(|(_, s)| s)
            .collect();
        let mut rng = Rng::new(45);
        let mut data = Vec::new();
        let executions = 3000;
        for i in 0..executions {
            data.clear();
            data.extend_from_slice(small[rng.below(small.len())]);
            mutate(&mut rng, &mut data, 1 << 16);
            let r = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| run(&mut det, &data)));
            assert!(r.is_ok(), "mutant {i} of seed 45 panicked the detector");
        }
    }
}
