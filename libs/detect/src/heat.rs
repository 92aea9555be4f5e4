//! The learned hub heatmap: a small convolutional network, trained on the project's renderer
//! (`scripts/train-hubnet.sh`), that maps a downscaled grey frame to the probability, per cell,
//! that the rotor's hub lies there. The geometric pipeline stays in charge of *where exactly*
//! the hub is (blade crossings, spinner rim); the heatmap says *which* of its candidates looks
//! like a hub at all, as one more ranker feature (`FeatureWeights::hub_heat`).
//!
//! A second network, [`HubCropNet`], places the chosen hub: it sees a crop of the working level
//! around the candidate at four times the heatmap's resolution, where the blades' edge crossings
//! sit a spinner radius or two beside an obliquely seen hub (`detect.default.hub_crop`).
//!
//! A third, [`HubYawNet`], reads the relative yaw from a view of fixed metric width around the
//! chosen hub (`detect.default.hub_yaw`), for the tracker to weigh with the hub–tower gap.
//!
//! The network input is the working pyramid level resized to [`NET_WIDTH`]×[`NET_HEIGHT`]
//! (area interpolation, aspect not kept): the same function makes the training set
//! (`hubtrack dataset`) and the detector's input, so the two cannot drift apart.

use opencv::core::{Mat, Size, Vector};
use opencv::prelude::*;
use opencv::{dnn, imgproc};

use crate::convnet::ConvNet;
use crate::DetectError;

/// Network input width, px.
pub const NET_WIDTH: i32 = 192;
/// Network input height, px.
pub const NET_HEIGHT: i32 = 128;
/// Input pixels per heatmap cell.
pub const NET_STRIDE: i32 = 8;

/// The model the build ships: written by `scripts/train-hubnet.sh` (ONNX, opset ≤ 13, input
/// `1×1×128×192` grey scaled to [0, 1], output `1×1×16×24` logits).
const MODEL: &[u8] = include_bytes!("../models/hubnet.onnx");
/// The still photos' model (`detect.default.still_models`): the same network trained with
/// photo-like rendered views too (`scripts/train-hubnet.sh`).
const STILL_MODEL: &[u8] = include_bytes!("../models/hubnet-still.onnx");

/// The network input of one working pyramid level: grey, resized to `NET_WIDTH`×`NET_HEIGHT`.
pub fn network_input(working: &Mat, out: &mut Mat) -> Result<(), DetectError> {
    crate::image::resize_area_grey(working, out, NET_WIDTH, NET_HEIGHT)
}

/// Hub probabilities on a grid of cells over the whole frame.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Heatmap {
    /// Cells per row.
    pub cols: usize,
    /// Rows of cells.
    pub rows: usize,
    /// Probability per cell, row-major.
    pub p: Vec<f32>,
}

impl Heatmap {
    /// The largest probability among the cells within `radius` cells of the point at
    /// fractions `(fx, fy)` of the frame's width and height (0 outside the frame). The hub may
    /// sit on a cell border, and the network's peak may be a cell off.
    pub fn near(&self, fx: f64, fy: f64, radius: f64) -> f64 {
        if self.p.is_empty() || !(0.0..=1.0).contains(&fx) || !(0.0..=1.0).contains(&fy) {
            return 0.0;
        }
        // Cell centres are at (i + 0.5) / cols.
        let (cx, cy) = (fx * self.cols as f64 - 0.5, fy * self.rows as f64 - 0.5);
        let (x0, x1) = (
            ((cx - radius).ceil().max(0.0)) as usize,
            ((cx + radius).floor().min(self.cols as f64 - 1.0)).max(0.0) as usize,
        );
        let (y0, y1) = (
            ((cy - radius).ceil().max(0.0)) as usize,
            ((cy + radius).floor().min(self.rows as f64 - 1.0)).max(0.0) as usize,
        );
        let mut best = 0.0f32;
        for y in y0..=y1 {
            for x in x0..=x1 {
                let (dx, dy) = (x as f64 - cx, y as f64 - cy);
                if dx * dx + dy * dy <= radius * radius + 1e-9 {
                    best = best.max(self.p[y * self.cols + x]);
                }
            }
        }
        best as f64
    }

    /// Where the most probable cell's hub lies, as fractions of the frame, and the cell's
    /// probability. The position is the probability-weighted mean of the cell centres in its
    /// 3×3 neighbourhood: the network was trained to a bump about a cell wide around the hub,
    /// so the neighbours' share says where in the cell the hub is.
    pub fn peak(&self) -> Option<([f64; 2], f64)> {
        let (i, p) = self
            .p
            .iter()
            .enumerate()
            .max_by(|a, b| a.1.total_cmp(b.1))?;
        let (x, y) = (i % self.cols, i / self.cols);
        let (mut sx, mut sy, mut sw) = (0.0, 0.0, 0.0);
        for ny in y.saturating_sub(1)..=(y + 1).min(self.rows - 1) {
            for nx in x.saturating_sub(1)..=(x + 1).min(self.cols - 1) {
                let w = self.p[ny * self.cols + nx] as f64;
                sx += w * (nx as f64 + 0.5);
                sy += w * (ny as f64 + 0.5);
                sw += w;
            }
        }
        let (cx, cy) = if sw > 0.0 {
            (sx / sw, sy / sw)
        } else {
            (x as f64 + 0.5, y as f64 + 0.5)
        };
        Some(([cx / self.cols as f64, cy / self.rows as f64], *p as f64))
    }
}

/// Side of the hub crop network's square input, px.
pub const CROP_SIDE: i32 = 64;
/// Crop pixels per cell of the crop network's output.
pub const CROP_STRIDE: i32 = 4;
/// The crop's side as a fraction of the working frame's height: a spinner seen from 12 m or
/// farther fits with its blade roots, and the candidates it refines (a spinner radius or two
/// off) leave the hub well inside. Fixed by training (`CROP_FRAC` in train-hubnet.py).
pub const CROP_FRAC: f64 = 0.3;
/// The crop model the build ships (`scripts/train-hubnet.sh`; ONNX, input `1×1×64×64` grey in
/// [0, 1], output `1×1×16×16` logits).
const CROP_MODEL: &[u8] = include_bytes!("../models/hubcrop.onnx");
/// The still photos' crop model (`detect.default.still_models`): the same network trained with
/// photo-like rendered views too (`scripts/train-hubnet.sh crop-still`), where a
/// nacelle seen from above points at the hub like a fourth blade.
const STILL_CROP_MODEL: &[u8] = include_bytes!("../models/hubcrop-still.onnx");

/// Where the crop network puts the hub near a candidate.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CropPeak {
    /// The hub, working px.
    pub hub: [f64; 2],
    /// The peak cell's probability.
    pub p: f64,
    /// The largest probability within one cell of the crop's centre (the candidate).
    pub at_centre: f64,
}

/// The hub crop network: a `CROP_FRAC`-of-the-height square of the working level around a
/// candidate, scaled to `CROP_SIDE`², to a probability per `CROP_STRIDE`² cell that the hub
/// lies there. Trained on the renderer (`train-hubnet.py --model crop`).
pub struct HubCropNet {
    net: Runner,
    crop: Mat,
}

impl HubCropNet {
    /// Load the shipped model; `direct` as for [`HubNet::new`].
    pub fn new(direct: bool) -> Result<HubCropNet, DetectError> {
        Ok(HubCropNet {
            net: Runner::load(CROP_MODEL, direct)?,
            crop: Mat::default(),
        })
    }

    /// Load the still photos' model.
    pub fn for_stills(direct: bool) -> Result<HubCropNet, DetectError> {
        Ok(HubCropNet {
            net: Runner::load(STILL_CROP_MODEL, direct)?,
            crop: Mat::default(),
        })
    }

    /// The hub near `centre` (working px) of the working level `working` (grey).
    pub fn run(&mut self, working: &Mat, centre: [f64; 2]) -> Result<CropPeak, DetectError> {
        self.run_scaled(working, centre, 1.0)
    }

    /// The same with the crop's side `scale` times the trained one.
    pub fn run_scaled(
        &mut self,
        working: &Mat,
        centre: [f64; 2],
        scale: f64,
    ) -> Result<CropPeak, DetectError> {
        let side = scale * CROP_FRAC * working.rows() as f64;
        let (x0, y0) = (centre[0] - side / 2.0, centre[1] - side / 2.0);
        warp_crop(working, centre, side, CROP_SIDE, &mut self.crop)?;
        let g = (CROP_SIDE / CROP_STRIDE) as usize;
        let map = probabilities(&mut self.net, &self.crop, (g, g), "hub crop network")?;
        let Some(([fx, fy], p)) = map.peak() else {
            unreachable!("a non-empty map has a peak")
        };
        Ok(CropPeak {
            hub: [x0 + fx * side, y0 + fy * side],
            p,
            at_centre: map.near(0.5, 0.5, 1.0),
        })
    }
}

/// Side of the yaw network's square input, px.
pub const YAW_SIDE: i32 = 64;
/// Width of the yaw network's view at the hub's distance, metres: the spinner, the blade roots,
/// the nacelle's sides and the tower top all fit (the nacelle reaches ~1.7 m beside the hub at
/// 10° of yaw). Fixed by training (`YAW_WINDOW_M` in train-hubnet.py).
pub const YAW_WINDOW_M: f64 = 8.0;
/// Width of the close-range yaw network's view at the hub's distance, metres (fixed by its
/// training, `train-hubnet.py --yaw-window-m`; see `detect.default.hub_yaw_close`).
pub const YAW_CLOSE_WINDOW_M: f64 = 8.0;
/// The yaw network's bins are centred from −`YAW_MAX_DEG` to +`YAW_MAX_DEG`, degrees ...
pub const YAW_MAX_DEG: f64 = 40.0;
/// ... evenly, this many.
pub const YAW_BINS: usize = 33;
/// The yaw model the build ships (`scripts/train-hubnet.sh yaw`: the thesis turbine and a
/// training family of other proportions; ONNX, input `1×1×64×64` grey in [0, 1], output
/// `1×33×1×1` logits).
const YAW_MODEL: &[u8] = include_bytes!("../models/hubyaw.onnx");
/// The same network trained on the thesis turbine alone (`scripts/train-hubnet.sh yaw-thesis`),
/// for that turbine (see `detect.default.hub_yaw_thesis_tolerance`).
const YAW_THESIS_MODEL: &[u8] = include_bytes!("../models/hubyaw-thesis.onnx");
/// The close-range yaw model (`scripts/train-hubnet.sh yaw-close`: the same network trained on
/// views from 3.5–14 m only, with a `YAW_CLOSE_WINDOW_M` window).
const YAW_CLOSE_MODEL: &[u8] = include_bytes!("../models/hubyaw-close.onnx");

/// The relative yaw the yaw network reads.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct YawReading {
    /// Mean of the network's yaw distribution, degrees (the sign of `TrackState::yaw_deg`:
    /// positive with the camera on the turbine's own left).
    pub yaw_deg: f64,
    /// Its standard deviation, degrees.
    pub std_deg: f64,
}

/// The yaw network: a `YAW_WINDOW_M`-wide square of the working level around the hub (its side
/// in px from the hub's distance), scaled to `YAW_SIDE`², to a distribution over `YAW_BINS`
/// relative yaws. What it reads is what the gap needs the tower for (the nacelle's sides, the
/// tower top beside the spinner, the spinner's shading), so it still reads when a blade
/// pointing down hides the tower. Trained on the renderer (`train-hubnet.py --model yaw`).
pub struct HubYawNet {
    net: Runner,
    /// Width of its view at the hub's distance, metres.
    window_m: f64,
    crop: Mat,
}

impl HubYawNet {
    /// Load the shipped model (the whole approach, 3.5–46 m); `direct` as for [`HubNet::new`].
    pub fn new(direct: bool) -> Result<HubYawNet, DetectError> {
        Ok(HubYawNet {
            net: Runner::load(YAW_MODEL, direct)?,
            window_m: YAW_WINDOW_M,
            crop: Mat::default(),
        })
    }

    /// Load the shipped model trained on the thesis turbine alone.
    pub fn thesis_turbine(direct: bool) -> Result<HubYawNet, DetectError> {
        Ok(HubYawNet {
            net: Runner::load(YAW_THESIS_MODEL, direct)?,
            window_m: YAW_WINDOW_M,
            crop: Mat::default(),
        })
    }

    /// Load the shipped close-range model (3.5–14 m, where the approach ends).
    pub fn close_range(direct: bool) -> Result<HubYawNet, DetectError> {
        Ok(HubYawNet {
            net: Runner::load(YAW_CLOSE_MODEL, direct)?,
            window_m: YAW_CLOSE_WINDOW_M,
            crop: Mat::default(),
        })
    }

    /// The yaw around `hub` (working px) of the working level `working` (grey), seen from
    /// `distance_m` with the focal length `focal_px` (working px).
    pub fn run(
        &mut self,
        working: &Mat,
        hub: [f64; 2],
        distance_m: f64,
        focal_px: f64,
    ) -> Result<YawReading, DetectError> {
        let side = focal_px * self.window_m / distance_m;
        warp_crop(working, hub, side, YAW_SIDE, &mut self.crop)?;
        let logits = self.net.run(&self.crop)?;
        if logits.len() != YAW_BINS {
            return Err(DetectError::BadImage(format!(
                "yaw network gave {} values for {YAW_BINS} bins",
                logits.len()
            )));
        }
        Ok(yaw_of_logits(logits))
    }
}

/// Mean and standard deviation of the softmax of the yaw network's logits over its bins.
pub fn yaw_of_logits(logits: &[f32]) -> YawReading {
    let top = logits.iter().copied().fold(f32::NEG_INFINITY, f32::max) as f64;
    let w: Vec<f64> = logits.iter().map(|&l| (l as f64 - top).exp()).collect();
    let sum: f64 = w.iter().sum();
    let n = logits.len().max(2) as f64;
    let centre = |i: usize| -YAW_MAX_DEG + 2.0 * YAW_MAX_DEG * i as f64 / (n - 1.0);
    let mean = w
        .iter()
        .enumerate()
        .map(|(i, p)| p * centre(i))
        .sum::<f64>()
        / sum;
    let var = w
        .iter()
        .enumerate()
        .map(|(i, p)| p * (centre(i) - mean).powi(2))
        .sum::<f64>()
        / sum;
    YawReading {
        yaw_deg: mean,
        std_deg: var.max(0.0).sqrt(),
    }
}

/// Cuts the `out_side`² square of side `side` (px) centred on `centre` out of `working`,
/// bilinear: crop pixel u samples x0 + (u + 0.5)·s − 0.5 (pixel centres), as the training crops
/// do; outside the frame the border repeats.
fn warp_crop(
    working: &Mat,
    centre: [f64; 2],
    side: f64,
    out_side: i32,
    out: &mut Mat,
) -> Result<(), DetectError> {
    let s = side / out_side as f64;
    let (x0, y0) = (centre[0] - side / 2.0, centre[1] - side / 2.0);
    let m = Mat::from_slice_2d(&[[s, 0.0, x0 + 0.5 * s - 0.5], [0.0, s, y0 + 0.5 * s - 0.5]])?;
    imgproc::warp_affine(
        working,
        out,
        &m,
        Size::new(out_side, out_side),
        imgproc::INTER_LINEAR | imgproc::WARP_INVERSE_MAP,
        opencv::core::BORDER_REPLICATE,
        opencv::core::Scalar::default(),
    )?;
    Ok(())
}

/// A network compiled into the detector and what runs it.
enum Runner {
    /// Our own kernels ([`ConvNet`]).
    Direct(ConvNet),
    /// OpenCV's dnn module, with its input and output buffers.
    Dnn { net: dnn::Net, blob: Mat, out: Mat },
}

impl Runner {
    /// Loads the ONNX `model`: with `direct`, for [`ConvNet`] where this CPU and the model
    /// allow it, else for the dnn module.
    fn load(model: &[u8], direct: bool) -> Result<Runner, DetectError> {
        if direct {
            if let Some(net) = ConvNet::from_onnx(model)? {
                return Ok(Runner::Direct(net));
            }
        }
        let net = dnn::read_net_from_onnx_buffer(&Vector::<u8>::from_slice(model))?;
        Ok(Runner::Dnn {
            net,
            blob: Mat::default(),
            out: Mat::default(),
        })
    }

    /// The network's output for the grey image `input`, scaled to [0, 1].
    fn run(&mut self, input: &Mat) -> Result<&[f32], DetectError> {
        match self {
            Runner::Direct(net) => {
                let (h, w) = (input.rows() as usize, input.cols() as usize);
                if input.is_continuous() {
                    net.run(input.data_bytes()?, h, w)
                } else {
                    net.run(input.try_clone()?.data_bytes()?, h, w)
                }
            }
            Runner::Dnn { net, blob, out } => {
                let size = input.size()?;
                dnn::blob_from_image_to(
                    input,
                    blob,
                    1.0 / 255.0,
                    size,
                    opencv::core::Scalar::default(),
                    false,
                    false,
                    opencv::core::CV_32F,
                )?;
                net.set_input(blob, "", 1.0, opencv::core::Scalar::default())?;
                *out = net.forward_single("")?;
                Ok(out.data_typed::<f32>()?)
            }
        }
    }
}

/// Runs `net` on the grey image `input` (scaled to [0, 1]) and returns its `cols`×`rows` logits
/// as probabilities; `what` names the network in the error when the model's output has another
/// size.
fn probabilities(
    net: &mut Runner,
    input: &Mat,
    (cols, rows): (usize, usize),
    what: &str,
) -> Result<Heatmap, DetectError> {
    let logits = net.run(input)?;
    if logits.len() != rows * cols {
        return Err(DetectError::BadImage(format!(
            "{what} gave {} values for {cols}x{rows} cells",
            logits.len()
        )));
    }
    Ok(Heatmap {
        cols,
        rows,
        p: logits.iter().map(|l| 1.0 / (1.0 + (-l).exp())).collect(),
    })
}

/// The loaded network and its buffers.
pub struct HubNet {
    net: Runner,
    input: Mat,
}

impl HubNet {
    /// Load the shipped model (video frames); `direct`: run it without the dnn module where
    /// the CPU allows (`detect.default.builtin_nets`).
    pub fn new(direct: bool) -> Result<HubNet, DetectError> {
        Ok(HubNet {
            net: Runner::load(MODEL, direct)?,
            input: Mat::default(),
        })
    }

    /// Load the still photos' model.
    pub fn for_stills(direct: bool) -> Result<HubNet, DetectError> {
        Ok(HubNet {
            net: Runner::load(STILL_MODEL, direct)?,
            input: Mat::default(),
        })
    }

    /// The heatmap of one working pyramid level (grey).
    pub fn run(&mut self, working: &Mat) -> Result<Heatmap, DetectError> {
        network_input(working, &mut self.input)?;
        let (rows, cols) = (
            (NET_HEIGHT / NET_STRIDE) as usize,
            (NET_WIDTH / NET_STRIDE) as usize,
        );
        probabilities(&mut self.net, &self.input, (cols, rows), "hub network")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_yaw_is_the_mean_and_spread_of_the_bin_distribution() {
        // Bin i is centred at −40 + 2.5·i degrees.
        let mut logits = vec![-30.0f32; YAW_BINS];
        logits[20] = 0.0;
        let r = yaw_of_logits(&logits);
        assert!((r.yaw_deg - 10.0).abs() < 1e-6 && r.std_deg < 1e-3, "{r:?}");
        // Two equal neighbours: halfway, spread half a bin.
        logits[21] = 0.0;
        let r = yaw_of_logits(&logits);
        assert!(
            (r.yaw_deg - 11.25).abs() < 1e-6 && (r.std_deg - 1.25).abs() < 1e-6,
            "{r:?}"
        );
        // A flat distribution: centred, as wide as 33 evenly spaced points: 2.5°·√((33² − 1)/12) = 23.80°.
        let r = yaw_of_logits(&[0.0f32; YAW_BINS]);
        assert!(
            r.yaw_deg.abs() < 1e-9 && (r.std_deg - 23.805).abs() < 0.01,
            "{r:?}"
        );
        // Large logits do not overflow.
        let r = yaw_of_logits(&[1e4f32; YAW_BINS]);
        assert!(r.yaw_deg.is_finite() && r.std_deg.is_finite());
    }

    fn map(cols: usize, rows: usize, hot: &[(usize, usize, f32)]) -> Heatmap {
        let mut p = vec![0.01; cols * rows];
        for &(x, y, v) in hot {
            p[y * cols + x] = v;
        }
        Heatmap { cols, rows, p }
    }

    #[test]
    fn near_takes_the_largest_cell_within_the_radius() {
        let m = map(24, 16, &[(10, 5, 0.9), (13, 5, 0.7)]);
        // Cell (10, 5) has its centre at (10.5 / 24, 5.5 / 16).
        let (fx, fy) = (10.5 / 24.0, 5.5 / 16.0);
        assert_eq!(m.near(fx, fy, 0.0), 0.9f32 as f64);
        // One cell to the right of (10, 5): both neighbours within 1 cell? (10,5) yes, (13,5) no.
        assert_eq!(m.near(11.5 / 24.0, fy, 1.0), 0.9f32 as f64);
        assert_eq!(m.near(12.5 / 24.0, fy, 1.0), 0.7f32 as f64);
        assert!((m.near(12.5 / 24.0, 12.5 / 16.0, 1.0) - 0.01).abs() < 1e-6);
        // Outside the frame: nothing.
        assert_eq!(m.near(-0.1, fy, 1.0), 0.0);
        assert_eq!(m.near(fx, 1.2, 1.0), 0.0);
        // The frame's corners clamp to the grid.
        assert!(m.near(0.0, 0.0, 1.0) > 0.0 && m.near(1.0, 1.0, 1.0) > 0.0);
    }

    #[test]
    fn the_peak_is_the_most_probable_cell_centre() {
        let m = map(24, 16, &[(3, 12, 0.4), (20, 2, 0.8)]);
        let (c, p) = m.peak().unwrap();
        assert!((c[0] - 20.5 / 24.0).abs() < 1e-12 && (c[1] - 2.5 / 16.0).abs() < 1e-12);
        assert!((p - 0.8).abs() < 1e-6);
        assert!(Heatmap::default().peak().is_none());
        // A strong right-hand neighbour moves the hub toward it, within the cell.
        let m = map(24, 16, &[(20, 2, 0.8), (21, 2, 0.6)]);
        let (c, p) = m.peak().unwrap();
        assert!((p - 0.8).abs() < 1e-6);
        assert!(c[0] > 20.5 / 24.0 && c[0] < 21.0 / 24.0, "{c:?}");
        assert!((c[1] - 2.5 / 16.0).abs() < 1e-9, "{c:?}");
    }

    #[test]
    fn the_shipped_model_loads_and_maps_the_whole_frame() {
        let mut net = HubNet::new(true).expect("the shipped model loads");
        let img = Mat::new_rows_cols_with_default(
            270,
            480,
            opencv::core::CV_8UC1,
            opencv::core::Scalar::all(100.0),
        )
        .unwrap();
        let h = net.run(&img).unwrap();
        assert_eq!(
            (h.cols, h.rows),
            (
                (NET_WIDTH / NET_STRIDE) as usize,
                (NET_HEIGHT / NET_STRIDE) as usize
            )
        );
        assert!(h.p.iter().all(|p| p.is_finite() && (0.0..=1.0).contains(p)));
        // A blank frame holds no hub.
        assert!(h.peak().unwrap().1 < 0.5, "{:?}", h.peak());
    }
}
