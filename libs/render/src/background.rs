//! Sky and ground: one pass over the whole frame, the dominant cost of a render.
//!
//! Every pixel needs its world viewing direction, which through the distorted lens is expensive to
//! compute. Instead the (exactly undistorted) directions of a grid of nodes every [`GRID`] pixels
//! are precomputed once per camera; per frame the nodes are rotated into the world and all smooth
//! quantities (sky gradient, sun glow, haze, sea reflection, ground/cloud plane intersection) are
//! evaluated per node. Rows interpolate the nodes vertically (only the kinds of node data the
//! adjacent cells need), then each 16-pixel segment steps linearly between its two row nodes and
//! does only the per-pixel texture work, in fixed point where it matters.
//!
//! Cell kinds: plain sky / ground cells interpolate texture coordinates linearly; cells near the
//! horizon where the footprint changes fast intersect the plane per pixel (one division) and
//! compute the haze per pixel; cells that straddle the horizon are split into 4-pixel pieces with
//! exact nodes, and only the pieces containing the horizon are evaluated per pixel.

use crate::camera::Camera;
use crate::math::{hash64, Rng, WorldToCam};
use crate::scene::{Ground, Scene, Sky};
use crate::texture::{mip_level, TexView, Textures};

/// Node spacing of the direction grid (pixels).
pub(crate) const GRID: usize = 16;
/// log2 of [`GRID`].
const GRID_LOG2: u32 = 4;
const _: () = assert!(1 << GRID_LOG2 == GRID);
/// Cloud base height above the ground (m).
const CLOUD_BASE_M: f64 = 1500.0;
/// Ground texel size (m).
const GROUND_TEXEL_M: f32 = 0.5;
/// Sea wave texel size (m).
const WAVE_TEXEL_M: f32 = 0.3;
/// Cloud texel size (m).
const CLOUD_TEXEL_M: f32 = 10.0;
/// The macro luminance map is the detail texture magnified by 2^MACRO_SHIFT (breaks up tiling).
const MACRO_SHIFT: u32 = 5;
/// Field rows are 2^FIELD_ROW_SHIFT ground texels high (128 m).
const FIELD_ROW_SHIFT: u32 = 8;
/// Field columns are 2^FIELD_COL_SHIFT ground texels wide (256 m).
const FIELD_COL_SHIFT: u32 = 9;
/// Ground and cloud intersections are clamped to this distance (m); haze hides anything beyond.
const FAR_M: f32 = 60_000.0;
/// Offset added to texture-plane coordinates so they stay positive (m).
const TEX_ORIGIN_OFFSET_M: f64 = 131_072.0;
/// Cells whose texture footprint varies more than this factor between corners get exact
/// per-pixel perspective instead of linear texture-coordinate interpolation.
const MAX_CELL_FOOT_RATIO: f32 = 2.0;
/// Crop-row stripes are 2^STRIPE_SHIFT ground texels wide (2 m period).
const STRIPE_SHIFT: u32 = 2;
/// Luminance drop of the dark crop-row stripes.
const STRIPE_DARKENING: f32 = 0.10;
/// Segments whose haze colour changes less than this (8-bit levels) use it as a constant.
const MAX_FLAT_HAZE_STEP_FIX: i32 = 3 << 14; // 0.75 level in 16.16
/// Segments whose gain (haze attenuation x macro luminance) changes by less than 2^-N of itself use it as a constant.
const MAX_FLAT_GAIN_SHIFT: u32 = 6;
/// Sky segments whose sky/cloud colours change less than this (8-bit levels) use them as constants.
const MAX_FLAT_SKY_STEP: f32 = 0.75;
/// Sky segments whose cloud fade changes less than this use it as a constant.
const MAX_FLAT_CLOUD_K_STEP: f32 = 0.004;
/// Sea segments whose colours/glint change less than this (8-bit levels) use them as constants.
const MAX_FLAT_HAZE_STEP_LEVELS: f32 = 0.75;
/// Sea segments whose haze fraction changes less than this use it as a constant.
const MAX_FLAT_FOG_STEP: f32 = 0.003;
/// Number of entries of the sky-gradient lookup table (by sine of elevation).
const SKY_LUT_N: usize = 256;
/// Number of field colours.
const PALETTE_N: usize = 8;

/// Per-node data, linearly interpolated between nodes.
#[derive(Clone, Copy, Debug, Default)]
struct Node {
    /// World direction (not normalised), z up.
    d: [f32; 3],
    /// Horizontal direction components along the texture axes.
    du: f32,
    dv: f32,
    /// Sky: sky colour. Sea: water colour (with reflected sky). Land: unused.
    a: [f32; 3],
    /// Sky: cloud colour. Ground: haze colour.
    b: [f32; 3],
    /// Sky: cloud visibility (fades toward the horizon). Sea: sun glint strength.
    k: f32,
    /// Texture footprint in metres per pixel (for mip selection).
    foot: f32,
    /// Ground: ground/sea texel coordinates of the intersection. Sky: cloud texel coordinates.
    u: f32,
    v: f32,
    /// Ground: haze fraction (0 = clear, 1 = only haze).
    f: f32,
}

impl Node {
    #[inline(always)]
    fn to_arr(self) -> [f32; 16] {
        let (d, a, b) = (self.d, self.a, self.b);
        [
            d[0], d[1], d[2], self.du, self.dv, a[0], a[1], a[2], b[0], b[1], b[2], self.k,
            self.foot, self.u, self.v, self.f,
        ]
    }

    #[inline(always)]
    fn from_arr(v: [f32; 16]) -> Node {
        Node {
            d: [v[0], v[1], v[2]],
            du: v[3],
            dv: v[4],
            a: [v[5], v[6], v[7]],
            b: [v[8], v[9], v[10]],
            k: v[11],
            foot: v[12],
            u: v[13],
            v: v[14],
            f: v[15],
        }
    }

    /// Linear interpolation of every field (written over a flat array so it vectorises).
    #[inline(always)]
    fn lerp(&self, o: &Node, t: f32) -> Node {
        let (x, y) = (self.to_arr(), o.to_arr());
        let mut r = [0f32; 16];
        for i in 0..16 {
            r[i] = x[i] + (y[i] - x[i]) * t;
        }
        Node::from_arr(r)
    }
}

/// Integer per-node data for the land kernel, computed once per row node (shared by the two
/// segments that meet there).
#[derive(Clone, Copy, Debug, Default)]
struct LandNode {
    /// Ground texel coordinates at mip level 0, 8 fractional bits.
    u: i32,
    v: i32,
    /// Haze colour · haze fraction, 16.16 fixed point.
    hz: [i32; 3],
    /// Haze attenuation · macro luminance, 131072 = 1.0.
    g: i32,
    /// Detail mip level for this node's footprint.
    level: u32,
    /// Footprint (m per pixel), kept for interpolation.
    foot: f32,
}

impl LandNode {
    #[inline(always)]
    fn new(n: &Node, tex: &Textures) -> LandNode {
        const FIX: f32 = 65536.0;
        let level = mip_level(n.foot / GROUND_TEXEL_M);
        let l2 = level.saturating_sub(MACRO_SHIFT);
        let (u, v) = (
            (n.u as f64 * 256.0) as i64 as i32,
            (n.v as f64 * 256.0) as i64 as i32,
        );
        let sh = 8 + MACRO_SHIFT + l2;
        let m = tex.grass.view(l2).get(u >> sh, v >> sh) as f32;
        LandNode {
            u,
            v,
            hz: [
                (n.b[0] * n.f * FIX) as i32,
                (n.b[1] * n.f * FIX) as i32,
                (n.b[2] * n.f * FIX) as i32,
            ],
            g: ((1.0 - n.f) * m * (131_072.0 / 128.0)) as i32,
            level,
            foot: n.foot,
        }
    }

    /// Interpolate between two grid rows; `t` in 0..GRID.
    #[inline(always)]
    fn lerp(&self, o: &LandNode, t: i32) -> LandNode {
        let l = |a: i32, b: i32| {
            a.wrapping_add(((b.wrapping_sub(a) as i64 * t as i64) >> GRID_LOG2) as i32)
        };
        let foot = self.foot + (o.foot - self.foot) * (t as f32 / GRID as f32);
        LandNode {
            u: l(self.u, o.u),
            v: l(self.v, o.v),
            hz: [
                l(self.hz[0], o.hz[0]),
                l(self.hz[1], o.hz[1]),
                l(self.hz[2], o.hz[2]),
            ],
            g: l(self.g, o.g),
            level: mip_level(foot / GROUND_TEXEL_M),
            foot,
        }
    }
}

/// Integer per-node data for the sky kernels (see [`LandNode`]).
#[derive(Clone, Copy, Debug, Default)]
struct SkyNode {
    /// Sky colour, 16.16 fixed point.
    a: [i32; 3],
    /// Cloud colour, 0..255.
    b: [i32; 3],
    /// Cloud visibility, 16.16 fixed point (65536 = 1).
    k: i32,
    /// Cloud texel coordinates at mip level 0, 8 fractional bits.
    u: i32,
    v: i32,
    /// Footprint (m per pixel) on the cloud plane.
    foot: f32,
}

impl SkyNode {
    #[inline(always)]
    fn new(n: &Node) -> SkyNode {
        const FIX: f32 = 65536.0;
        SkyNode {
            a: [
                (n.a[0] * FIX) as i32,
                (n.a[1] * FIX) as i32,
                (n.a[2] * FIX) as i32,
            ],
            b: [
                n.b[0].min(255.0) as i32,
                n.b[1].min(255.0) as i32,
                n.b[2].min(255.0) as i32,
            ],
            k: (n.k * FIX) as i32,
            u: (n.u as f64 * 256.0) as i64 as i32,
            v: (n.v as f64 * 256.0) as i64 as i32,
            foot: n.foot,
        }
    }

    /// Interpolate between two grid rows; `t` in 0..GRID.
    #[inline(always)]
    fn lerp(&self, o: &SkyNode, t: i32) -> SkyNode {
        let l = |a: i32, b: i32| {
            a.wrapping_add(((b.wrapping_sub(a) as i64 * t as i64) >> GRID_LOG2) as i32)
        };
        SkyNode {
            a: [
                l(self.a[0], o.a[0]),
                l(self.a[1], o.a[1]),
                l(self.a[2], o.a[2]),
            ],
            b: [
                l(self.b[0], o.b[0]),
                l(self.b[1], o.b[1]),
                l(self.b[2], o.b[2]),
            ],
            k: l(self.k, o.k),
            u: l(self.u, o.u),
            v: l(self.v, o.v),
            foot: self.foot + (o.foot - self.foot) * (t as f32 / GRID as f32),
        }
    }
}

/// What a grid cell needs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum CellKind {
    /// Sky; cloud coordinates (if any) interpolated linearly.
    Sky,
    /// Sky near the horizon where the cloud plane recedes fast: per-pixel plane intersection.
    SkyPersp,
    /// Ground; texture coordinates interpolated linearly.
    Ground,
    /// Ground near the horizon: per-pixel plane intersection (one division per pixel).
    GroundPersp,
    /// Straddles the horizon: everything evaluated per pixel.
    Exact,
}

/// Everything about the current frame that the per-pixel kernels need.
struct FrameCtx {
    ground: Ground,
    /// Land detail from the shrub texture instead of the grass one ([`Scene::shrubland`]).
    shrubland: bool,
    eye_z: f32,
    /// Camera position in texture-plane coordinates (m, offset positive).
    eye_u: f32,
    eye_v: f32,
    cloud_eye_u: f32,
    cloud_eye_v: f32,
    /// Ground (or sea) texels per metre.
    ground_tpm: f32,
    glow_lut: [f32; GLOW_LUT_N],
    fog_lut: [f32; FOG_LUT_N],
    inv_visibility: f32,
    sun: [f32; 3],
    sky_lut: [[f32; 3]; SKY_LUT_N],
    glow_col: [f32; 3],
    glow_strength: f32,
    haze: [f32; 3],
    tex_cos: f32,
    tex_sin: f32,
    water: [f32; 3],
    glint_strength: f32,
    /// Field palette (0..255 RGB) per mip level: far levels fade toward the mean so field edges
    /// do not alias.
    palette_i: [[[i32; 3]; PALETTE_N]; crate::texture::TEX_LEVELS],
    /// Darkening (detail-texture units, 128 = 1.0) of crop-row stripes (drawn at mip level 0 only).
    stripe_amp: i32,
    field_seed: u32,
    cloud_alpha: [f32; 256],
    cloud_shade: [f32; 256],
    /// `cloud_alpha` in 1/256 units.
    cloud_alpha_q: [u32; 256],
    /// Extra mip levels for the cloud texture (softer, cheaper; overcast decks are diffuse).
    cloud_mip_bias: u32,
    /// `cloud_alpha · cloud_shade` in 1/256 units.
    cloud_ash_q: [u32; 256],
    cloud_col: [f32; 3],
    has_clouds: bool,
    f_px: f32,
}

/// Sky/ground renderer with its camera-dependent precomputation.
pub(crate) struct Background {
    w: usize,
    h: usize,
    gw: usize,
    gh: usize,
    /// Camera-frame undistorted normalised rays (x/z, y/z) of the grid nodes.
    node_ray: Vec<[f32; 2]>,
    nodes: Vec<Node>,
    cells: Vec<CellKind>,
    row: Vec<Node>,
    land_row: Vec<LandNode>,
    land_nodes: Vec<LandNode>,
    sky_row: Vec<SkyNode>,
    sky_nodes: Vec<SkyNode>,
    /// Per grid row and node column: which interpolated node kinds the adjacent cells need
    /// ([`NEED_NODE`], [`NEED_LAND`]), so rows only interpolate what is used.
    need: Vec<u8>,
    tex: Textures,
    f_px: f32,
}

impl Background {
    pub fn new(cam: &Camera) -> Background {
        let (w, h) = (cam.width as usize, cam.height as usize);
        let gw = (w.max(2) - 1).div_ceil(GRID) + 1;
        let gh = (h.max(2) - 1).div_ceil(GRID) + 1;
        let mut node_ray = Vec::with_capacity(gw * gh);
        for j in 0..gh {
            for i in 0..gw {
                let r = cam.unproject([(i * GRID) as f64, (j * GRID) as f64]);
                node_ray.push([r[0] as f32, r[1] as f32]);
            }
        }
        Background {
            w,
            h,
            gw,
            gh,
            node_ray,
            nodes: vec![Node::default(); gw * gh],
            cells: vec![CellKind::Exact; (gw - 1) * (gh - 1)],
            row: vec![Node::default(); gw],
            land_row: vec![LandNode::default(); gw],
            land_nodes: vec![LandNode::default(); gw * gh],
            sky_row: vec![SkyNode::default(); gw],
            sky_nodes: vec![SkyNode::default(); gw * gh],
            need: vec![0; gw * gh],
            tex: Textures::new(),
            f_px: cam.fx as f32,
        }
    }

    /// Haze colour (0..255 RGB) at the horizon for a scene: distant objects fade to it.
    pub fn haze_and_visibility(scene: &Scene) -> ([f32; 3], f64) {
        let (lut, _, _, _) = sky_palette(scene.sky);
        (lut_sky(&lut, 0.0), visibility_m(scene.sky))
    }

    /// Fill `out` (BGR8, full frame) with sky and ground for this camera pose.
    pub fn render(&mut self, out: &mut [u8], scene: &Scene, w2c: &WorldToCam) {
        let ctx = self.frame_ctx(scene, w2c);
        // Nodes: rotate rays into the world, evaluate smooth quantities.
        for (n, r) in self.nodes.iter_mut().zip(&self.node_ray) {
            let dw = w2c.dir_to_world([r[0] as f64, r[1] as f64, 1.0]);
            *n = eval_node(&ctx, [dw[0] as f32, dw[1] as f32, dw[2] as f32]);
        }
        for (l, n) in self.sky_nodes.iter_mut().zip(&self.nodes) {
            *l = if n.d[2] > 0.0 {
                SkyNode::new(n)
            } else {
                SkyNode::default()
            };
        }
        if ctx.ground != Ground::Sea {
            for (l, n) in self.land_nodes.iter_mut().zip(&self.nodes) {
                *l = if n.d[2] < 0.0 {
                    LandNode::new(n, &self.tex)
                } else {
                    LandNode::default()
                };
            }
        }
        let cw = self.gw - 1;
        for j in 0..self.gh - 1 {
            for i in 0..cw {
                let c = [
                    &self.nodes[j * self.gw + i],
                    &self.nodes[j * self.gw + i + 1],
                    &self.nodes[(j + 1) * self.gw + i],
                    &self.nodes[(j + 1) * self.gw + i + 1],
                ];
                // Footprint spread over the cell says how non-linear the plane mapping is.
                let (fmin, fmax) = c
                    .iter()
                    .fold((f32::MAX, 0f32), |(a, b), n| (a.min(n.foot), b.max(n.foot)));
                let linear = fmax <= fmin * MAX_CELL_FOOT_RATIO;
                let kind = if c.iter().all(|n| n.d[2] > 0.0) {
                    let clouds = ctx.has_clouds && c.iter().any(|n| n.k > 0.0);
                    if !clouds || linear {
                        CellKind::Sky
                    } else {
                        CellKind::SkyPersp
                    }
                } else if c.iter().all(|n| n.d[2] < 0.0) {
                    if linear {
                        CellKind::Ground
                    } else {
                        CellKind::GroundPersp
                    }
                } else {
                    CellKind::Exact
                };
                self.cells[j * cw + i] = kind;
            }
        }
        let land = ctx.ground != Ground::Sea;
        for j in 0..self.gh - 1 {
            for i in 0..self.gw {
                let mut m = 0u8;
                for c in [i.wrapping_sub(1), i] {
                    if c >= cw {
                        continue;
                    }
                    m |= match self.cells[j * cw + c] {
                        CellKind::Sky => NEED_SKY,
                        CellKind::Ground if land => NEED_LAND,
                        CellKind::GroundPersp if land => NEED_LAND | NEED_NODE,
                        _ => NEED_NODE,
                    };
                }
                self.need[j * self.gw + i] = m;
            }
        }
        let w = self.w;
        for y in 0..self.h {
            let j = y / GRID;
            let t = (y % GRID) as f32 / GRID as f32;
            let (r0, r1) = (j * self.gw, (j + 1).min(self.gh - 1) * self.gw);
            let ti = (y % GRID) as i32;
            let need = &self.need[j * self.gw..(j + 1) * self.gw];
            for i in 0..self.gw {
                if need[i] & NEED_NODE != 0 {
                    self.row[i] = self.nodes[r0 + i].lerp(&self.nodes[r1 + i], t);
                }
                if need[i] & NEED_LAND != 0 {
                    self.land_row[i] = self.land_nodes[r0 + i].lerp(&self.land_nodes[r1 + i], ti);
                }
                if need[i] & NEED_SKY != 0 {
                    self.sky_row[i] = self.sky_nodes[r0 + i].lerp(&self.sky_nodes[r1 + i], ti);
                }
            }
            let orow = &mut out[y * w * 3..(y + 1) * w * 3];
            for i in 0..cw {
                let x0 = i * GRID;
                if x0 >= w {
                    break;
                }
                let x1 = (x0 + GRID).min(w);
                let seg = &mut orow[x0 * 3..x1 * 3];
                let (n0, n1) = (&self.row[i], &self.row[i + 1]);
                let tex = &self.tex;
                let (l0, l1) = (&self.land_row[i], &self.land_row[i + 1]);
                match self.cells[j * cw + i] {
                    CellKind::Sky => {
                        sky_int_span(&ctx, tex, seg, &self.sky_row[i], &self.sky_row[i + 1])
                    }
                    CellKind::SkyPersp => sky_span(&ctx, tex, seg, n0, n1, true),
                    CellKind::Ground if ctx.ground != Ground::Sea => {
                        land_span(&ctx, tex, seg, l0, l1, None)
                    }
                    CellKind::GroundPersp if ctx.ground != Ground::Sea => {
                        land_span(&ctx, tex, seg, l0, l1, Some((n0, n1)))
                    }
                    CellKind::Ground => sea_span(&ctx, tex, seg, n0, n1, false),
                    CellKind::GroundPersp => sea_span(&ctx, tex, seg, n0, n1, true),
                    CellKind::Exact => exact_span(&ctx, tex, seg, n0, n1),
                }
            }
        }
    }

    fn frame_ctx(&self, scene: &Scene, w2c: &WorldToCam) -> FrameCtx {
        let mut rng = Rng::new(scene.seed, 0xB6);
        let (sky_lut, glow_col, glow_strength, cloud_col) = sky_palette(scene.sky);
        let tex_angle = if scene.ground == Ground::Sea {
            // Wave crests (the texture's long axis) run across the wind, which blows along the
            // rotor axis: perpendicular to the usual line of sight, as seen on real sea.
            std::f64::consts::FRAC_PI_2 - scene.nacelle_yaw_deg.to_radians()
                + rng.range(-0.25, 0.25)
        } else {
            rng.range(0.0, std::f64::consts::TAU)
        };
        let (tex_sin, tex_cos) = tex_angle.sin_cos();
        let (ox, oy) = (rng.range(0.0, 20_000.0), rng.range(0.0, 20_000.0));
        let (cox, coy) = (rng.range(0.0, 20_000.0), rng.range(0.0, 20_000.0));
        let eye = w2c.origin;
        let to_tex = |x: f64, y: f64| -> (f32, f32) {
            (
                (tex_cos * x + tex_sin * y + TEX_ORIGIN_OFFSET_M) as f32,
                (-tex_sin * x + tex_cos * y + TEX_ORIGIN_OFFSET_M) as f32,
            )
        };
        let (eye_u, eye_v) = to_tex(eye[0] + ox, eye[1] + oy);
        let (cloud_eye_u, cloud_eye_v) = to_tex(eye[0] + cox, eye[1] + coy);
        let sun = scene.sun_dir();
        let ground_light = match scene.sky {
            Sky::Clear => 1.0,
            Sky::Clouds => 0.92,
            Sky::Overcast => 0.78,
        } * (0.75
            + 0.25 * (scene.sun_elevation_deg.to_radians().sin() as f32).clamp(0.0, 1.0) / 0.7);
        // Field colours (0..255 RGB): greens, dry grass, wheat, ploughed soil.
        let mut base_pal: [[f32; 3]; PALETTE_N] = [
            [84.0, 122.0, 52.0],
            [104.0, 138.0, 60.0],
            [70.0, 104.0, 46.0],
            [142.0, 146.0, 78.0],
            [176.0, 160.0, 96.0],
            [122.0, 100.0, 72.0],
            [94.0, 128.0, 56.0],
            [116.0, 134.0, 68.0],
        ];
        let tint = [
            rng.range(0.92, 1.08) as f32,
            rng.range(0.95, 1.05) as f32,
            rng.range(0.9, 1.1) as f32,
        ];
        for p in base_pal.iter_mut() {
            for c in 0..3 {
                p[c] *= tint[c] * ground_light;
            }
        }
        let mean = base_pal.iter().fold([0f32; 3], |a, p| {
            [a[0] + p[0] / 8.0, a[1] + p[1] / 8.0, a[2] + p[2] / 8.0]
        });
        let mut palette = [[[0f32; 3]; PALETTE_N]; crate::texture::TEX_LEVELS];
        for (l, pal) in palette.iter_mut().enumerate() {
            // Ground texels are 0.5 m; fields are >= 128 m: fade contrast once a pixel covers ~16 m.
            let contrast = (1.0 - (l as f32 - 4.0) / 3.0).clamp(0.0, 1.0);
            for (k, p) in pal.iter_mut().enumerate() {
                for c in 0..3 {
                    p[c] = mean[c] + (base_pal[k][c] - mean[c]) * contrast;
                }
            }
        }
        let stripe_amp = (128.0 * STRIPE_DARKENING) as i32;
        let palette_i = palette.map(|l| l.map(|p| p.map(|c| c as i32)));
        let coverage = match scene.sky {
            Sky::Clouds => rng.range(0.38, 0.62) as f32,
            _ => 0.0,
        };
        let mut cloud_alpha = [0f32; 256];
        let mut cloud_shade = [0f32; 256];
        for n in 0..256 {
            let v = n as f64 / 255.0;
            match scene.sky {
                Sky::Clouds => {
                    let c = coverage as f64;
                    cloud_alpha[n] = crate::math::smoothstep(c, c + 0.22, v) as f32;
                    cloud_shade[n] =
                        (1.0 - 0.22 * crate::math::smoothstep(c + 0.08, c + 0.45, v)) as f32;
                }
                Sky::Overcast => {
                    cloud_alpha[n] = (0.55 * crate::math::smoothstep(0.25, 0.85, v)) as f32;
                    cloud_shade[n] = 1.0;
                }
                Sky::Clear => {}
            }
        }
        let water = match scene.sky {
            Sky::Clear => [18.0, 52.0, 76.0],
            Sky::Clouds => [22.0, 54.0, 74.0],
            Sky::Overcast => [44.0, 58.0, 66.0],
        };
        let glint_strength = match scene.sky {
            Sky::Clear => 230.0,
            Sky::Clouds => 170.0,
            Sky::Overcast => 0.0,
        };
        FrameCtx {
            ground: scene.ground,
            shrubland: scene.shrubland,
            eye_z: eye[2] as f32,
            eye_u,
            eye_v,
            cloud_eye_u,
            cloud_eye_v,
            ground_tpm: 1.0
                / if scene.ground == Ground::Sea {
                    WAVE_TEXEL_M
                } else {
                    GROUND_TEXEL_M
                },
            glow_lut: glow_lut(glow_strength),
            fog_lut: fog_lut(),
            inv_visibility: 1.0 / visibility_m(scene.sky) as f32,
            sun: [sun[0] as f32, sun[1] as f32, sun[2] as f32],
            haze: lut_sky(&sky_lut, 0.0),
            sky_lut,
            glow_col,
            glow_strength,
            tex_cos: tex_cos as f32,
            tex_sin: tex_sin as f32,
            water,
            glint_strength,
            palette_i,
            stripe_amp,
            field_seed: (hash64(scene.seed ^ 0xF1E1D) >> 32) as u32,
            cloud_mip_bias: if scene.sky == Sky::Overcast { 2 } else { 0 },
            cloud_alpha_q: cloud_alpha.map(|a| (a * 256.0 + 0.5) as u32),
            cloud_ash_q: std::array::from_fn(|i| {
                (cloud_alpha[i] * cloud_shade[i] * 256.0 + 0.5) as u32
            }),
            cloud_alpha,
            cloud_shade,
            cloud_col,
            has_clouds: scene.sky != Sky::Clear,
            f_px: self.f_px,
        }
    }
}

/// Meteorological visibility per sky (m): sets how fast distant things fade into haze.
fn visibility_m(sky: Sky) -> f64 {
    match sky {
        Sky::Clear => 14_000.0,
        Sky::Clouds => 11_000.0,
        Sky::Overcast => 6_500.0,
    }
}

/// Sky gradient table (by sine of elevation), sun glow colour and strength, cloud colour.
fn sky_palette(sky: Sky) -> ([[f32; 3]; SKY_LUT_N], [f32; 3], f32, [f32; 3]) {
    // (horizon, zenith, exponent) in 0..255 RGB.
    let (hor, zen, ex, glow, cloud) = match sky {
        Sky::Clear => (
            [188.0, 208.0, 228.0],
            [62.0, 112.0, 192.0],
            3.0,
            1.0,
            [245.0, 245.0, 243.0],
        ),
        Sky::Clouds => (
            [192.0, 210.0, 228.0],
            [78.0, 128.0, 200.0],
            2.5,
            0.8,
            [246.0, 246.0, 244.0],
        ),
        Sky::Overcast => (
            [172.0, 176.0, 182.0],
            [204.0, 207.0, 212.0],
            1.5,
            0.15,
            [150.0, 154.0, 160.0],
        ),
    };
    let mut lut = [[0f32; 3]; SKY_LUT_N];
    for (i, e) in lut.iter_mut().enumerate() {
        let s = i as f32 / (SKY_LUT_N - 1) as f32;
        let t = 1.0 - (1.0 - s).powf(ex);
        for c in 0..3 {
            e[c] = hor[c] + (zen[c] - hor[c]) * t;
        }
    }
    (lut, [255.0, 246.0, 225.0], glow, cloud)
}

#[inline]
fn lut_sky(lut: &[[f32; 3]; SKY_LUT_N], s: f32) -> [f32; 3] {
    let i = ((s.clamp(0.0, 1.0) * (SKY_LUT_N - 1) as f32) + 0.5) as usize;
    lut[i.min(SKY_LUT_N - 1)]
}

/// Entries of the sun-glow table, indexed by the chord distance `sqrt(2 (1 - cos angle))` in [0, 2].
const GLOW_LUT_N: usize = 512;
/// Entries of the haze table, indexed by distance / visibility in [0, FOG_LUT_RANGE].
const FOG_LUT_N: usize = 1024;
/// Range of the haze table in units of the visibility.
const FOG_LUT_RANGE: f32 = 8.0;

/// Sun glow (fraction of the glow colour) per chord distance to the sun direction.
fn glow_lut(strength: f32) -> [f32; GLOW_LUT_N] {
    let mut lut = [0f32; GLOW_LUT_N];
    for (i, v) in lut.iter_mut().enumerate() {
        let chord = 2.0 * i as f32 / (GLOW_LUT_N - 1) as f32; // ≈ angle (rad) near the sun
        *v = strength * (0.45 * (-chord / 0.10).exp() + 0.22 * (-chord / 0.5).exp());
    }
    lut
}

/// Haze fraction `1 - exp(-x)` for `x` = distance / visibility.
fn fog_lut() -> [f32; FOG_LUT_N] {
    let mut lut = [0f32; FOG_LUT_N];
    for (i, v) in lut.iter_mut().enumerate() {
        *v = 1.0 - (-(i as f32) * FOG_LUT_RANGE / (FOG_LUT_N - 1) as f32).exp();
    }
    lut
}

#[inline(always)]
fn glow(ctx: &FrameCtx, cos_angle: f32) -> f32 {
    let chord = (2.0 * (1.0 - cos_angle).max(0.0)).sqrt();
    ctx.glow_lut[((chord * ((GLOW_LUT_N - 1) as f32 / 2.0)) as usize).min(GLOW_LUT_N - 1)]
}

#[inline(always)]
fn fog(ctx: &FrameCtx, dist: f32) -> f32 {
    let x = dist * ctx.inv_visibility * ((FOG_LUT_N - 1) as f32 / FOG_LUT_RANGE);
    ctx.fog_lut[(x as usize).min(FOG_LUT_N - 1)]
}

/// Evaluate all smooth per-direction quantities for one world direction.
fn eval_node(ctx: &FrameCtx, d: [f32; 3]) -> Node {
    let len = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt().max(1e-12);
    let inv_len = 1.0 / len;
    let s = d[2] * inv_len;
    let du = ctx.tex_cos * d[0] + ctx.tex_sin * d[1];
    let dv = -ctx.tex_sin * d[0] + ctx.tex_cos * d[1];
    let horiz = (du * du + dv * dv).sqrt().max(1e-9);
    let cos_sun = (d[0] * ctx.sun[0] + d[1] * ctx.sun[1] + d[2] * ctx.sun[2]) * inv_len;
    let g = glow(ctx, cos_sun);
    let mut n = Node {
        d,
        du,
        dv,
        ..Node::default()
    };
    if d[2] > 0.0 {
        let sky = lut_sky(&ctx.sky_lut, s);
        // Clamped so the fixed-point gradient kernel never overflows a byte.
        n.a = [
            (sky[0] + ctx.glow_col[0] * g).min(255.0),
            (sky[1] + ctx.glow_col[1] * g).min(255.0),
            (sky[2] + ctx.glow_col[2] * g).min(255.0),
        ];
        if ctx.has_clouds {
            let t = ((CLOUD_BASE_M as f32 - ctx.eye_z) / d[2]).clamp(0.0, FAR_M / horiz);
            let dist = t * len;
            n.k = crate::math::smoothstep(0.0, 0.16, s as f64) as f32;
            n.foot = dist / ctx.f_px / s.max(0.02).sqrt();
            n.u = (ctx.cloud_eye_u + t * du) / CLOUD_TEXEL_M;
            n.v = (ctx.cloud_eye_v + t * dv) / CLOUD_TEXEL_M;
            // Clouds are lit from the sun side: brighter toward the sun.
            let lit = 0.92 + 0.25 * g / ctx.glow_strength.max(1e-3);
            n.b = [
                ctx.cloud_col[0] * lit,
                ctx.cloud_col[1] * lit,
                ctx.cloud_col[2] * lit,
            ];
        }
    } else {
        let t = (-ctx.eye_z / d[2]).min(FAR_M / horiz);
        let dist = t * len;
        let f = fog(ctx, dist);
        let hz = 0.5 * g;
        n.f = f;
        n.b = [
            ctx.haze[0] + ctx.glow_col[0] * hz,
            ctx.haze[1] + ctx.glow_col[1] * hz,
            ctx.haze[2] + ctx.glow_col[2] * hz,
        ];
        let graze = (-s).max(1e-3);
        n.foot = dist / ctx.f_px / graze.sqrt();
        n.u = (ctx.eye_u + t * du) * ctx.ground_tpm;
        n.v = (ctx.eye_v + t * dv) * ctx.ground_tpm;
        if ctx.ground == Ground::Sea {
            // Fresnel (Schlick) mix of water body colour and reflected sky.
            let m = 1.0 - graze;
            let fres = 0.02 + 0.98 * (m * m) * (m * m) * m;
            let refl = lut_sky(&ctx.sky_lut, graze);
            for c in 0..3 {
                n.a[c] = ctx.water[c] * (1.0 - fres) + refl[c] * fres * 0.9;
            }
            // Glint: reflected ray (dx, dy, -dz) against the sun.
            let cos_r = (d[0] * ctx.sun[0] + d[1] * ctx.sun[1] - d[2] * ctx.sun[2]) * inv_len;
            let ang2 = 2.0 * (1.0 - cos_r).max(0.0);
            // Glitter path: a bright core plus a wide halo (wave slopes spread the reflection).
            n.k = ctx.glint_strength * (0.6 * (-ang2 / 0.004).exp() + 0.4 * (-ang2 / 0.04).exp());
        }
    }
    n
}

#[inline(always)]
fn store(px: &mut [u8], r: f32, g: f32, b: f32) {
    px[0] = b as u8;
    px[1] = g as u8;
    px[2] = r as u8;
}

/// Produces the integer texel coordinates of successive pixels of a segment.
trait UvGen {
    /// Texel coordinates of the current pixel; then advance one pixel.
    fn next_uv(&mut self) -> (i32, i32);
    /// Texel coordinates of pixel `k` if they can be predicted exactly (linear generators).
    fn predict(&self, k: i32) -> Option<(i32, i32)>;
}

/// Linear stepping of texture coordinates between two nodes (8 fractional bits).
#[derive(Clone, Copy, Debug)]
struct Affine {
    u: i32,
    v: i32,
    du: i32,
    dv: i32,
}

impl Affine {
    /// Coordinates in texels of mip `level` (node coordinates are level-0 texels).
    #[inline(always)]
    fn new(n0: &Node, n1: &Node, level: u32) -> Affine {
        let k = 256.0 / (1u32 << level) as f32;
        let ks = k / GRID as f32;
        Affine {
            u: (n0.u as f64 * k as f64) as i64 as i32,
            v: (n0.v as f64 * k as f64) as i64 as i32,
            du: ((n1.u - n0.u) * ks) as i32,
            dv: ((n1.v - n0.v) * ks) as i32,
        }
    }
}

impl UvGen for Affine {
    #[inline(always)]
    fn next_uv(&mut self) -> (i32, i32) {
        let r = (self.u >> 8, self.v >> 8);
        self.u = self.u.wrapping_add(self.du);
        self.v = self.v.wrapping_add(self.dv);
        r
    }

    #[inline(always)]
    fn predict(&self, k: i32) -> Option<(i32, i32)> {
        Some((
            self.u.wrapping_add(self.du.wrapping_mul(k)) >> 8,
            self.v.wrapping_add(self.dv.wrapping_mul(k)) >> 8,
        ))
    }
}

/// Linear stepping from precomputed integer node coordinates (8 fractional bits, mip level applied).
#[derive(Clone, Copy, Debug)]
struct AffineI {
    u: i32,
    v: i32,
    du: i32,
    dv: i32,
}

impl UvGen for AffineI {
    #[inline(always)]
    fn next_uv(&mut self) -> (i32, i32) {
        let r = (self.u >> 8, self.v >> 8);
        self.u = self.u.wrapping_add(self.du);
        self.v = self.v.wrapping_add(self.dv);
        r
    }

    #[inline(always)]
    fn predict(&self, k: i32) -> Option<(i32, i32)> {
        Some((
            self.u.wrapping_add(self.du.wrapping_mul(k)) >> 8,
            self.v.wrapping_add(self.dv.wrapping_mul(k)) >> 8,
        ))
    }
}

/// Exact per-pixel intersection with a horizontal plane `dh` metres above the eye, from linearly
/// interpolated ray directions (one division per pixel).
#[derive(Clone, Copy, Debug)]
struct Persp {
    dz: f32,
    ddz: f32,
    du: f32,
    ddu: f32,
    dv: f32,
    ddv: f32,
    eu: f32,
    ev: f32,
    dh: f32,
    /// 1 / (texels per metre), to recover metric ray lengths for the haze.
    inv_tpm: f32,
    tmax: f32,
}

impl Persp {
    /// Coordinates in texels of mip `level` (`texels_per_m` refers to level 0).
    fn new(
        ctx: &FrameCtx,
        n0: &Node,
        n1: &Node,
        dh: f32,
        texels_per_m: f32,
        clouds: bool,
        level: u32,
    ) -> Persp {
        let inv = 1.0 / GRID as f32;
        let texels_per_m = texels_per_m / (1u32 << level) as f32;
        let (eu, ev) = if clouds {
            (ctx.cloud_eye_u, ctx.cloud_eye_v)
        } else {
            (ctx.eye_u, ctx.eye_v)
        };
        let horiz = |n: &Node| (n.du * n.du + n.dv * n.dv).sqrt();
        Persp {
            dz: n0.d[2],
            ddz: (n1.d[2] - n0.d[2]) * inv,
            du: n0.du * texels_per_m,
            ddu: (n1.du - n0.du) * inv * texels_per_m,
            dv: n0.dv * texels_per_m,
            ddv: (n1.dv - n0.dv) * inv * texels_per_m,
            eu: eu * texels_per_m,
            ev: ev * texels_per_m,
            dh,
            inv_tpm: 1.0 / texels_per_m,
            tmax: FAR_M / horiz(n0).max(horiz(n1)).max(1e-9),
        }
    }

    /// Texel coordinates and the metric distance along the ray to the plane; then advance.
    #[inline(always)]
    fn next_uvd(&mut self) -> ((i32, i32), f32) {
        let t = (self.dh / self.dz).clamp(0.0, self.tmax);
        let r = (
            (self.eu + t * self.du) as i32,
            (self.ev + t * self.dv) as i32,
        );
        let h2 = (self.du * self.du + self.dv * self.dv) * (self.inv_tpm * self.inv_tpm);
        let dist = t * (h2 + self.dz * self.dz).sqrt();
        self.dz += self.ddz;
        self.du += self.ddu;
        self.dv += self.ddv;
        (r, dist)
    }
}

impl UvGen for Persp {
    #[inline(always)]
    fn next_uv(&mut self) -> (i32, i32) {
        self.next_uvd().0
    }

    fn predict(&self, _k: i32) -> Option<(i32, i32)> {
        None
    }
}

/// Field cell at ground texel `(u, v)`: rows of fixed height, columns staggered per row.
/// Returns (row, column, hash); hash bits 29.. pick the colour, bit 28 stripes, bit 27 their direction.
#[inline(always)]
fn field_at(seed: u32, u: i32, v: i32) -> (u32, u32, u32) {
    let row = (v >> FIELD_ROW_SHIFT) as u32;
    let hr = row.wrapping_mul(0x9E37_79B1) ^ seed;
    let col = ((u as u32).wrapping_add(hr & 0x1FF) >> FIELD_COL_SHIFT) ^ (hr >> 7);
    let mut h = col.wrapping_mul(0x85EB_CA77) ^ row.wrapping_mul(0xC2B2_AE3D);
    h ^= h >> 15;
    h = h.wrapping_mul(0x2C1B_3C6D);
    h ^= h >> 13;
    (row, col, h)
}

/// Sky pixels of one segment, interpolating between nodes `n0` and `n1` (one grid step apart).
fn sky_span(ctx: &FrameCtx, tex: &Textures, seg: &mut [u8], n0: &Node, n1: &Node, persp: bool) {
    if !ctx.has_clouds || (n0.k <= 0.0 && n1.k <= 0.0) {
        // Plain gradient: 16.16 fixed-point colour steps (node colours are clamped to 0..255).
        const ONE: f32 = 65536.0;
        let inv = ONE / GRID as f32;
        let mut c = [
            (n0.a[0] * ONE) as i32,
            (n0.a[1] * ONE) as i32,
            (n0.a[2] * ONE) as i32,
        ];
        let dc = [
            ((n1.a[0] - n0.a[0]) * inv) as i32,
            ((n1.a[1] - n0.a[1]) * inv) as i32,
            ((n1.a[2] - n0.a[2]) * inv) as i32,
        ];
        for px in seg.chunks_exact_mut(3) {
            px[0] = (c[2] >> 16) as u8;
            px[1] = (c[1] >> 16) as u8;
            px[2] = (c[0] >> 16) as u8;
            c = [c[0] + dc[0], c[1] + dc[1], c[2] + dc[2]];
        }
        return;
    }
    let level = mip_level(n0.foot.min(n1.foot) / CLOUD_TEXEL_M);
    let view = tex.clouds.view(level);
    if persp {
        let g = Persp::new(
            ctx,
            n0,
            n1,
            CLOUD_BASE_M as f32 - ctx.eye_z,
            1.0 / CLOUD_TEXEL_M,
            true,
            level,
        );
        cloud_pixels(ctx, view, seg, n0, n1, g);
    } else {
        cloud_pixels(ctx, view, seg, n0, n1, Affine::new(n0, n1, level));
    }
}

fn cloud_pixels<G: UvGen>(
    ctx: &FrameCtx,
    view: TexView,
    seg: &mut [u8],
    n0: &Node,
    n1: &Node,
    mut gen: G,
) {
    let flat = (0..3).all(|c| {
        (n1.a[c] - n0.a[c]).abs() < MAX_FLAT_SKY_STEP
            && (n1.b[c] - n0.b[c]).abs() < MAX_FLAT_SKY_STEP
    }) && (n1.k - n0.k).abs() < MAX_FLAT_CLOUD_K_STEP;
    if flat {
        // Integer path: colour = (sky · (256 - alpha) + cloud · alpha · shade) / 256 with
        // per-segment sky/cloud colours and fade, per-texel alpha from the tables.
        let k = ((0.5 * (n0.k + n1.k)) * 256.0) as u32;
        let a = [0, 1, 2].map(|c| (0.5 * (n0.a[c] + n1.a[c])).clamp(0.0, 255.0) as u32);
        let b = [0, 1, 2].map(|c| (0.5 * (n0.b[c] + n1.b[c])).clamp(0.0, 255.0) as u32);
        for px in seg.chunks_exact_mut(3) {
            let (u, v) = gen.next_uv();
            let c = view.get(u, v) as usize;
            let al = (ctx.cloud_alpha_q[c] * k) >> 8;
            let sh = (ctx.cloud_ash_q[c] * k) >> 8;
            let ia = 256 - al;
            px[0] = ((a[2] * ia + b[2] * sh) >> 8) as u8;
            px[1] = ((a[1] * ia + b[1] * sh) >> 8) as u8;
            px[2] = ((a[0] * ia + b[0] * sh) >> 8) as u8;
        }
        return;
    }
    let inv = 1.0 / GRID as f32;
    let mut a = n0.a;
    let da = [
        (n1.a[0] - a[0]) * inv,
        (n1.a[1] - a[1]) * inv,
        (n1.a[2] - a[2]) * inv,
    ];
    let mut k = n0.k;
    let dk = (n1.k - k) * inv;
    let b = n0.b;
    for px in seg.chunks_exact_mut(3) {
        let (u, v) = gen.next_uv();
        let c = view.get(u, v) as usize;
        let al = ctx.cloud_alpha[c] * k;
        let sh = ctx.cloud_shade[c] * al;
        let ia = 1.0 - al;
        store(
            px,
            a[0] * ia + b[0] * sh,
            a[1] * ia + b[1] * sh,
            a[2] * ia + b[2] * sh,
        );
        a = [a[0] + da[0], a[1] + da[1], a[2] + da[2]];
        k += dk;
    }
}

/// [`Background::need`] flag: the float node is used.
const NEED_NODE: u8 = 1;
/// [`Background::need`] flag: the integer land node is used.
const NEED_LAND: u8 = 2;
/// [`Background::need`] flag: the integer sky node is used.
const NEED_SKY: u8 = 4;

/// Sky pixels of one segment from integer row nodes (cells away from the horizon).
fn sky_int_span(ctx: &FrameCtx, tex: &Textures, seg: &mut [u8], s0: &SkyNode, s1: &SkyNode) {
    let dc = [0, 1, 2].map(|c| (s1.a[c] - s0.a[c]) >> GRID_LOG2);
    if !ctx.has_clouds || (s0.k <= 0 && s1.k <= 0) {
        // Plain gradient: 16.16 fixed-point colour steps (node colours are clamped to 0..255).
        let mut c = s0.a;
        for px in seg.chunks_exact_mut(3) {
            px[0] = (c[2] >> 16) as u8;
            px[1] = (c[1] >> 16) as u8;
            px[2] = (c[0] >> 16) as u8;
            c = [c[0] + dc[0], c[1] + dc[1], c[2] + dc[2]];
        }
        return;
    }
    let level = (mip_level(s0.foot.min(s1.foot) / CLOUD_TEXEL_M) + ctx.cloud_mip_bias)
        .min(crate::texture::TEX_LEVELS as u32 - 1);
    let view = tex.clouds.view(level);
    let mut g = AffineI {
        u: s0.u >> level,
        v: s0.v >> level,
        du: s1.u.wrapping_sub(s0.u) >> (level + GRID_LOG2),
        dv: s1.v.wrapping_sub(s0.v) >> (level + GRID_LOG2),
    };
    // Sky colour, cloud colour and fade change slowly: constants per segment (midpoint), the
    // sky gradient itself is stepped.
    let k = ((s0.k >> 1) + (s1.k >> 1)) >> 8; // 0..256
    let b = [0, 1, 2].map(|c| ((s0.b[c] + s1.b[c]) >> 1) as u32);
    let mut a = s0.a;
    for px in seg.chunks_exact_mut(3) {
        let (u, v) = g.next_uv();
        let t = view.get(u, v) as usize;
        let al = (ctx.cloud_alpha_q[t] * k as u32) >> 8;
        let sh = (ctx.cloud_ash_q[t] * k as u32) >> 8;
        let ia = 256 - al;
        px[0] = (((a[2] >> 16) as u32 * ia + b[2] * sh) >> 8) as u8;
        px[1] = (((a[1] >> 16) as u32 * ia + b[1] * sh) >> 8) as u8;
        px[2] = (((a[0] >> 16) as u32 * ia + b[0] * sh) >> 8) as u8;
        a = [a[0] + dc[0], a[1] + dc[1], a[2] + dc[2]];
    }
}

/// Sub-segment length (pixels) inside cells that straddle the horizon.
const SUB: usize = 4;

/// A segment of a cell that straddles the horizon: exact nodes every [`SUB`] pixels; sub-segments
/// that are entirely sky or ground are interpolated (ground with exact perspective), the ones
/// containing the horizon are evaluated per pixel.
fn exact_span(ctx: &FrameCtx, tex: &Textures, seg: &mut [u8], n0: &Node, n1: &Node) {
    const NSUB: usize = GRID / SUB;
    let mut e = [Node::default(); NSUB + 1];
    for (q, en) in e.iter_mut().enumerate() {
        *en = eval_node(ctx, n0.lerp(n1, (q * SUB) as f32 / GRID as f32).d);
    }
    // The span kernels step by 1/GRID of the node difference: stretch sub-segment ends.
    let stretch = (GRID / SUB) as f32;
    for (q, sub) in seg.chunks_mut(SUB * 3).enumerate() {
        let (a, b) = (&e[q], &e[q + 1]);
        if a.d[2] > 0.0 && b.d[2] > 0.0 {
            let far = a.lerp(b, stretch);
            sky_span(ctx, tex, sub, a, &far, true);
        } else if a.d[2] < 0.0 && b.d[2] < 0.0 {
            let far = a.lerp(b, stretch);
            if ctx.ground == Ground::Sea {
                sea_span(ctx, tex, sub, a, &far, true);
            } else {
                let (la, lb) = (LandNode::new(a, tex), LandNode::new(&far, tex));
                land_span(ctx, tex, sub, &la, &lb, Some((a, &far)));
            }
        } else {
            for (k, px) in sub.chunks_exact_mut(3).enumerate() {
                let n = eval_node(ctx, a.lerp(b, k as f32 / SUB as f32).d);
                if n.d[2] > 0.0 {
                    sky_span(ctx, tex, px, &n, &n, false);
                } else if ctx.ground == Ground::Sea {
                    sea_span(ctx, tex, px, &n, &n, false);
                } else {
                    let l = LandNode::new(&n, tex);
                    land_span(ctx, tex, px, &l, &l, None);
                }
            }
        }
    }
}

/// Sea pixels of one segment; `persp` = exact per-pixel plane intersection and haze.
fn sea_span(ctx: &FrameCtx, tex: &Textures, seg: &mut [u8], n0: &Node, n1: &Node, persp: bool) {
    let level = mip_level(n0.foot.min(n1.foot) / WAVE_TEXEL_M);
    let inv = 1.0 / GRID as f32;
    let w1 = tex.waves.view(level);
    // Long swell: the same texture 8x larger and turned 90°; smooth, so sampled per segment.
    let l2 = level.saturating_sub(3);
    let w2 = tex.waves.view(l2);
    let sh = 3 + l2;
    let s0 = w2.get(n0.v as i32 >> sh, n0.u as i32 >> sh) as f32;
    let s1 = w2.get(n1.v as i32 >> sh, n1.u as i32 >> sh) as f32;
    let mut sw = s0;
    let dsw = (s1 - s0) * inv;
    let (mut a, mut b) = (n0.a, n0.b);
    let da = [
        (n1.a[0] - a[0]) * inv,
        (n1.a[1] - a[1]) * inv,
        (n1.a[2] - a[2]) * inv,
    ];
    let db = [
        (n1.b[0] - b[0]) * inv,
        (n1.b[1] - b[1]) * inv,
        (n1.b[2] - b[2]) * inv,
    ];
    let (mut k, mut f) = (n0.k, n0.f);
    let (dk, df) = ((n1.k - k) * inv, (n1.f - f) * inv);
    let mut affine = Affine::new(n0, n1, level);
    let flat = (0..3).all(|c| {
        (n1.a[c] - n0.a[c]).abs() < MAX_FLAT_HAZE_STEP_LEVELS
            && (n1.b[c] - n0.b[c]).abs() < MAX_FLAT_HAZE_STEP_LEVELS
    }) && (n1.f - n0.f).abs() < MAX_FLAT_FOG_STEP
        && (n1.k - n0.k).abs() < MAX_FLAT_HAZE_STEP_LEVELS;
    if !persp && flat {
        // Integer path with per-segment water colour, haze and glint (midpoints); the swell
        // gain is stepped. With lum = w·swell/128²:
        // colour = (water·lum + glint·(0.25 + 2.5·max(0, lum − 0.9)))·(1 − haze) + haze colour·haze
        let m = |x: f32, y: f32| 0.5 * (x + y);
        let fm = m(n0.f, n1.f);
        let cf = 1.0 - fm;
        let km = m(n0.k, n1.k) * cf;
        // Fixed point: luminance `lum` in 1/128 units, colours accumulated in 1/256 units, so
        // water·(1 − haze)·lum_real = (2·water·(1 − haze))·lum / 256.
        let aq = [0, 1, 2].map(|c| (m(n0.a[c], n1.a[c]) * cf * 2.0) as i32);
        let cq = [0, 1, 2].map(|c| ((km * 0.25 + m(n0.b[c], n1.b[c]) * fm) * 256.0) as i32);
        let kq = (km * 2.5 * 2.0) as i32;
        let thr = (0.9 * 128.0) as i32; // glitter threshold 0.9 in 1/128 units
        let mut swq = (s0 * 256.0) as i32;
        let dswq = ((s1 - s0) * 256.0 * inv) as i32;
        for px in seg.chunks_exact_mut(3) {
            let (u, v) = affine.next_uv();
            // lum in 1/128 units: w (128 = 1) · swell (128 = 1) / 128.
            let lum = (w1.get(u, v) as i32 * (swq >> 8)) >> 7;
            let spark = kq * (lum - thr).max(0);
            let r = (aq[0] * lum + spark + cq[0]) >> 8;
            let g = (aq[1] * lum + spark + cq[1]) >> 8;
            let b = (aq[2] * lum + spark + cq[2]) >> 8;
            px[0] = b.clamp(0, 255) as u8;
            px[1] = g.clamp(0, 255) as u8;
            px[2] = r.clamp(0, 255) as u8;
            swq += dswq;
        }
        return;
    }
    let mut persp_gen =
        persp.then(|| Persp::new(ctx, n0, n1, -ctx.eye_z, ctx.ground_tpm, false, level));
    const NORM: f32 = 1.0 / (128.0 * 128.0);
    for px in seg.chunks_exact_mut(3) {
        let ((u, v), fog_px) = match persp_gen.as_mut() {
            Some(g) => {
                let (uv, dist) = g.next_uvd();
                (uv, fog(ctx, dist))
            }
            None => (affine.next_uv(), f),
        };
        let w = w1.get(u, v) as f32;
        let lum = w * sw * NORM;
        let spark = k * (0.25 + (lum - 0.9).max(0.0) * 2.5);
        let cf = 1.0 - fog_px;
        store(
            px,
            (a[0] * lum + spark) * cf + b[0] * fog_px,
            (a[1] * lum + spark) * cf + b[1] * fog_px,
            (a[2] * lum + spark * 0.95) * cf + b[2] * fog_px,
        );
        a = [a[0] + da[0], a[1] + da[1], a[2] + da[2]];
        b = [b[0] + db[0], b[1] + db[1], b[2] + db[2]];
        sw += dsw;
        k += dk;
        f += df;
    }
}

/// Land pixels of one segment between row nodes `l0` and `l1`. With `persp` (the float nodes),
/// texture coordinates and haze come from an exact per-pixel plane intersection (cells near the
/// horizon, where the haze changes within a few pixels).
fn land_span(
    ctx: &FrameCtx,
    tex: &Textures,
    seg: &mut [u8],
    l0: &LandNode,
    l1: &LandNode,
    persp: Option<(&Node, &Node)>,
) {
    let level = l0.level.min(l1.level);
    match persp {
        None => {
            let g = AffineI {
                u: l0.u >> level,
                v: l0.v >> level,
                du: l1.u.wrapping_sub(l0.u) >> (level + GRID_LOG2),
                dv: l1.v.wrapping_sub(l0.v) >> (level + GRID_LOG2),
            };
            land_pixels(ctx, tex, seg, l0, l1, level, g)
        }
        Some((n0, n1)) => land_persp_pixels(ctx, tex, seg, n0, n1, level),
    }
}

/// The land's detail texture: fields or shrubland.
fn land_detail<'a>(ctx: &FrameCtx, tex: &'a Textures) -> &'a crate::texture::MipTex {
    if ctx.shrubland {
        &tex.shrubs
    } else {
        &tex.grass
    }
}

/// Land pixels with exact per-pixel perspective and haze (float path, used near the horizon).
fn land_persp_pixels(
    ctx: &FrameCtx,
    tex: &Textures,
    seg: &mut [u8],
    n0: &Node,
    n1: &Node,
    level: u32,
) {
    let inv = 1.0 / GRID as f32;
    let det = land_detail(ctx, tex).view(level);
    let pal = &ctx.palette_i[level as usize];
    let l2 = level.saturating_sub(MACRO_SHIFT);
    let mac = tex.grass.view(l2);
    let sh = MACRO_SHIFT + l2;
    let m0 = mac.get(n0.u as i32 >> sh, n0.v as i32 >> sh) as f32;
    let m1 = mac.get(n1.u as i32 >> sh, n1.v as i32 >> sh) as f32;
    let (mut m, dm) = (m0, (m1 - m0) * inv);
    let mut b = n0.b;
    let db = [
        (n1.b[0] - b[0]) * inv,
        (n1.b[1] - b[1]) * inv,
        (n1.b[2] - b[2]) * inv,
    ];
    let mut g = Persp::new(ctx, n0, n1, -ctx.eye_z, ctx.ground_tpm, false, level);
    let fs = ctx.field_seed;
    const NORM: f32 = 1.0 / (128.0 * 128.0);
    for px in seg.chunks_exact_mut(3) {
        let ((ui, vi), dist) = g.next_uvd();
        let f = fog(ctx, dist);
        let p = &pal[(field_at(fs, ui << level, vi << level).2 >> 29) as usize];
        let lum = det.get(ui, vi) as f32 * m * NORM * (1.0 - f);
        store(
            px,
            p[0] as f32 * lum + b[0] * f,
            p[1] as f32 * lum + b[1] * f,
            p[2] as f32 * lum + b[2] * f,
        );
        m += dm;
        b = [b[0] + db[0], b[1] + db[1], b[2] + db[2]];
    }
}

fn land_pixels<G: UvGen>(
    ctx: &FrameCtx,
    tex: &Textures,
    seg: &mut [u8],
    l0: &LandNode,
    l1: &LandNode,
    level: u32,
    mut gen: G,
) {
    let det = land_detail(ctx, tex).view(level);
    let pal = &ctx.palette_i[level as usize];
    let fs = ctx.field_seed;
    // Stripes only at full texture resolution (they would alias otherwise).
    let stripe_on = if level == 0 { ctx.stripe_amp } else { 0 };
    let n = (seg.len() / 3) as i32;
    // Most segments lie inside one field: look its colour up once.
    let (f0, single) = match (gen.predict(0), gen.predict(n - 1)) {
        (Some((u0, v0)), Some((u1, v1))) => {
            let (a, b) = (
                field_at(fs, u0 << level, v0 << level),
                field_at(fs, u1 << level, v1 << level),
            );
            (a.2, a.0 == b.0 && a.1 == b.1)
        }
        _ => (0, false),
    };
    // Fast path: one field, gain and haze nearly constant along the segment (the usual case):
    // colour = (palette · gain) · detail + haze with per-segment constants.
    let haze_flat = (0..3).all(|c| (l1.hz[c] - l0.hz[c]).abs() < MAX_FLAT_HAZE_STEP_FIX);
    let gain_flat = (l1.g - l0.g).abs() < (l0.g.abs() >> MAX_FLAT_GAIN_SHIFT).max(1);
    if single && haze_flat && gain_flat {
        let p = &pal[(f0 >> 29) as usize];
        // Stripe darkening: select the u or v coordinate with masks (no branch in the loop).
        let amp = if (f0 >> 28) & 1 == 1 { stripe_on } else { 0 };
        let (mu, mv) = if f0 & (1 << 27) != 0 {
            (-1i32, 0i32)
        } else {
            (0, -1)
        };
        let gm = ((l0.g >> 1) + (l1.g >> 1)) >> 8;
        let pg = [p[0] * gm, p[1] * gm, p[2] * gm];
        let hz = [
            (l0.hz[0] + l1.hz[0]) >> 17,
            (l0.hz[1] + l1.hz[1]) >> 17,
            (l0.hz[2] + l1.hz[2]) >> 17,
        ];
        for px in seg.chunks_exact_mut(3) {
            let (ui, vi) = gen.next_uv();
            let d = det.get(ui, vi) as i32 - ((((ui & mu) | (vi & mv)) >> STRIPE_SHIFT) & 1) * amp;
            px[0] = (((pg[2] * d) >> 16) + hz[2]).min(255) as u8;
            px[1] = (((pg[1] * d) >> 16) + hz[1]).min(255) as u8;
            px[2] = (((pg[0] * d) >> 16) + hz[0]).min(255) as u8;
        }
        return;
    }
    let mut g = l0.g;
    let dg = (l1.g - l0.g) >> GRID_LOG2;
    let mut bb = l0.hz;
    let dbb = [
        (l1.hz[0] - l0.hz[0]) >> GRID_LOG2,
        (l1.hz[1] - l0.hz[1]) >> GRID_LOG2,
        (l1.hz[2] - l0.hz[2]) >> GRID_LOG2,
    ];
    for px in seg.chunks_exact_mut(3) {
        let (ui, vi) = gen.next_uv();
        let h = if single {
            f0
        } else {
            field_at(fs, ui << level, vi << level).2
        };
        let p = &pal[(h >> 29) as usize];
        // Crop rows / mowing stripes in some fields: darker every other 2^STRIPE_SHIFT texels.
        let sv = if h & (1 << 27) != 0 { ui } else { vi };
        let dark = ((h >> 28) as i32 & 1 & (sv >> STRIPE_SHIFT)) * stripe_on;
        // Detail (128 = 1.0) times the gain (131072 = 1.0) -> luminance with 256 = 1.0.
        let lum = ((det.get(ui, vi) as i32 - dark) * (g >> 8)) >> 8;
        // p (0..255) * lum (256 = 1.0) >> 8, plus haze.
        let r = ((p[0] * lum) >> 8) + (bb[0] >> 16);
        let gg = ((p[1] * lum) >> 8) + (bb[1] >> 16);
        let bl = ((p[2] * lum) >> 8) + (bb[2] >> 16);
        px[0] = bl.min(255) as u8;
        px[1] = gg.min(255) as u8;
        px[2] = r.min(255) as u8;
        g += dg;
        bb = [bb[0] + dbb[0], bb[1] + dbb[1], bb[2] + dbb[2]];
    }
}
