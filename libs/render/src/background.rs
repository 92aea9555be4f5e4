//! Sky and ground: one pass over the whole frame, the dominant cost of a render.
//!
//! Every pixel needs its world viewing direction, which through the distorted lens is expensive to
//! compute. Instead the (exactly undistorted) directions of a grid of nodes every [`GRID`] pixels
//! are precomputed once per camera; per frame the nodes are rotated into the world and all smooth
//! quantities (sky gradient, sun glow, haze, sea reflection) are evaluated per node. Pixels then
//! interpolate linearly between nodes and only do the cheap per-pixel work: the ground/cloud plane
//! intersection (one division, so texture perspective is exact) and texture lookups.
//! Cells that straddle the horizon are evaluated exactly per pixel.

use crate::camera::Camera;
use crate::math::{hash64, Rng, WorldToCam};
use crate::scene::{Ground, Scene, Sky};
use crate::texture::{mip_level, Textures};

/// Node spacing of the direction grid (pixels).
pub(crate) const GRID: usize = 8;
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
const MAX_CELL_FOOT_RATIO: f32 = 1.2;
/// Crop-row stripes are 2^STRIPE_SHIFT ground texels wide (2 m period).
const STRIPE_SHIFT: u32 = 2;
/// Luminance drop of the dark crop-row stripes.
const STRIPE_DARKENING: f32 = 0.10;
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
    /// Sky: sky colour. Land: (1 - haze) in a[0]. Sea: water colour · (1 - haze).
    a: [f32; 3],
    /// Sky: cloud colour. Ground: haze colour · haze fraction.
    b: [f32; 3],
    /// Sky: cloud visibility (fades toward the horizon). Sea: sun glint strength.
    k: f32,
    /// Texture footprint in metres per pixel (for mip selection).
    foot: f32,
    /// Ground: ground/sea texel coordinates of the intersection. Sky: cloud texel coordinates.
    u: f32,
    v: f32,
}

impl Node {
    #[inline(always)]
    fn to_arr(self) -> [f32; 16] {
        let (d, a, b) = (self.d, self.a, self.b);
        [d[0], d[1], d[2], self.du, self.dv, a[0], a[1], a[2], b[0], b[1], b[2], self.k, self.foot, self.u, self.v, 0.0]
    }

    #[inline(always)]
    fn from_arr(v: [f32; 16]) -> Node {
        Node { d: [v[0], v[1], v[2]], du: v[3], dv: v[4], a: [v[5], v[6], v[7]], b: [v[8], v[9], v[10]], k: v[11], foot: v[12], u: v[13], v: v[14] }
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
    eye_z: f32,
    /// Camera position in texture-plane coordinates (m, offset positive).
    eye_u: f64,
    eye_v: f64,
    cloud_eye_u: f64,
    cloud_eye_v: f64,
    sun: [f32; 3],
    sky_lut: [[f32; 3]; SKY_LUT_N],
    glow_col: [f32; 3],
    glow_strength: f32,
    haze: [f32; 3],
    visibility_m: f32,
    tex_cos: f32,
    tex_sin: f32,
    water: [f32; 3],
    glint_strength: f32,
    /// Field palette (0..255 RGB) per mip level: far levels fade toward the mean so field edges
    /// do not alias.
    palette_i: [[[i32; 3]; PALETTE_N]; crate::texture::TEX_LEVELS],
    /// Darkening (detail-texture units, 128 = 1.0) of crop-row stripes per mip level (0 once they would alias).
    stripe_amp: [i32; crate::texture::TEX_LEVELS],
    field_seed: u32,
    cloud_alpha: [f32; 256],
    cloud_shade: [f32; 256],
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
                let (fmin, fmax) = c.iter().fold((f32::MAX, 0f32), |(a, b), n| (a.min(n.foot), b.max(n.foot)));
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
        let w = self.w;
        for y in 0..self.h {
            let j = y / GRID;
            let t = (y % GRID) as f32 / GRID as f32;
            let (r0, r1) = (j * self.gw, (j + 1).min(self.gh - 1) * self.gw);
            for i in 0..self.gw {
                self.row[i] = self.nodes[r0 + i].lerp(&self.nodes[r1 + i], t);
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
                match self.cells[j * cw + i] {
                    CellKind::Sky => sky_span(&ctx, tex, seg, n0, n1, Affine::new(n0, n1)),
                    CellKind::SkyPersp => {
                        let g = Persp::new(&ctx, n0, n1, CLOUD_BASE_M as f32 - ctx.eye_z, 1.0 / CLOUD_TEXEL_M, true);
                        sky_span(&ctx, tex, seg, n0, n1, g)
                    }
                    CellKind::Ground => ground_span(&ctx, tex, seg, n0, n1, Affine::new(n0, n1)),
                    CellKind::GroundPersp => {
                        let g = Persp::new(&ctx, n0, n1, -ctx.eye_z, ctx.ground_tpm, false);
                        ground_span(&ctx, tex, seg, n0, n1, g)
                    }
                    CellKind::Exact => {
                        for (k, px) in seg.chunks_exact_mut(3).enumerate() {
                            let d = n0.lerp(n1, k as f32 / GRID as f32).d;
                            let n = eval_node(&ctx, d);
                            if d[2] > 0.0 {
                                sky_span(&ctx, tex, px, &n, &n, Affine::new(&n, &n));
                            } else {
                                ground_span(&ctx, tex, px, &n, &n, Affine::new(&n, &n));
                            }
                        }
                    }
                }
            }
        }
    }

    fn frame_ctx(&self, scene: &Scene, w2c: &WorldToCam) -> FrameCtx {
        let mut rng = Rng::new(scene.seed, 0xB6);
        let (sky_lut, glow_col, glow_strength, cloud_col) = sky_palette(scene.sky);
        let tex_angle = rng.range(0.0, std::f64::consts::TAU);
        let (tex_sin, tex_cos) = tex_angle.sin_cos();
        let (ox, oy) = (rng.range(0.0, 20_000.0), rng.range(0.0, 20_000.0));
        let (cox, coy) = (rng.range(0.0, 20_000.0), rng.range(0.0, 20_000.0));
        let eye = w2c.origin;
        let to_tex = |x: f64, y: f64| -> (f64, f64) {
            (tex_cos * x + tex_sin * y + TEX_ORIGIN_OFFSET_M, -tex_sin * x + tex_cos * y + TEX_ORIGIN_OFFSET_M)
        };
        let (eye_u, eye_v) = to_tex(eye[0] + ox, eye[1] + oy);
        let (cloud_eye_u, cloud_eye_v) = to_tex(eye[0] + cox, eye[1] + coy);
        let sun = scene.sun_dir();
        let ground_light = match scene.sky {
            Sky::Clear => 1.0,
            Sky::Clouds => 0.92,
            Sky::Overcast => 0.78,
        } * (0.75 + 0.25 * (scene.sun_elevation_deg.to_radians().sin() as f32).clamp(0.0, 1.0) / 0.7);
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
        let tint = [rng.range(0.92, 1.08) as f32, rng.range(0.95, 1.05) as f32, rng.range(0.9, 1.1) as f32];
        for p in base_pal.iter_mut() {
            for c in 0..3 {
                p[c] *= tint[c] * ground_light;
            }
        }
        let mean = base_pal.iter().fold([0f32; 3], |a, p| [a[0] + p[0] / 8.0, a[1] + p[1] / 8.0, a[2] + p[2] / 8.0]);
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
        let mut stripe_amp = [0i32; crate::texture::TEX_LEVELS];
        stripe_amp[0] = (128.0 * STRIPE_DARKENING) as i32;
        stripe_amp[1] = (64.0 * STRIPE_DARKENING) as i32;
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
                    cloud_shade[n] = (1.0 - 0.22 * crate::math::smoothstep(c + 0.08, c + 0.45, v)) as f32;
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
            eye_z: eye[2] as f32,
            eye_u,
            eye_v,
            cloud_eye_u,
            cloud_eye_v,
            sun: [sun[0] as f32, sun[1] as f32, sun[2] as f32],
            haze: lut_sky(&sky_lut, 0.0),
            sky_lut,
            glow_col,
            glow_strength,
            visibility_m: visibility_m(scene.sky) as f32,
            tex_cos: tex_cos as f32,
            tex_sin: tex_sin as f32,
            water,
            glint_strength,
            palette_i,
            stripe_amp,
            field_seed: (hash64(scene.seed ^ 0xF1E1D) >> 32) as u32,
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
        Sky::Clear => ([188.0, 208.0, 228.0], [62.0, 112.0, 192.0], 3.0, 1.0, [245.0, 245.0, 243.0]),
        Sky::Clouds => ([192.0, 210.0, 228.0], [78.0, 128.0, 200.0], 2.5, 0.8, [246.0, 246.0, 244.0]),
        Sky::Overcast => ([172.0, 176.0, 182.0], [204.0, 207.0, 212.0], 1.5, 0.15, [150.0, 154.0, 160.0]),
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

/// Sun glow added to the sky around the sun, as a fraction of the glow colour.
#[inline]
fn glow(ctx: &FrameCtx, cos_angle: f32) -> f32 {
    let ang = (2.0 * (1.0 - cos_angle).max(0.0)).sqrt(); // ≈ angle in radians near the sun
    ctx.glow_strength * (0.45 * (-ang / 0.10).exp() + 0.22 * (-ang / 0.5).exp())
}

/// Evaluate all smooth per-direction quantities for one world direction.
fn eval_node(ctx: &FrameCtx, d: [f32; 3]) -> Node {
    let len = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt().max(1e-12);
    let s = d[2] / len;
    let du = ctx.tex_cos * d[0] + ctx.tex_sin * d[1];
    let dv = -ctx.tex_sin * d[0] + ctx.tex_cos * d[1];
    let cos_sun = (d[0] * ctx.sun[0] + d[1] * ctx.sun[1] + d[2] * ctx.sun[2]) / len;
    let g = glow(ctx, cos_sun);
    let mut n = Node { d, du, dv, ..Node::default() };
    if d[2] > 0.0 {
        let sky = lut_sky(&ctx.sky_lut, s);
        // Clamped so the fixed-point gradient kernel never overflows a byte.
        n.a = [
            (sky[0] + ctx.glow_col[0] * g).min(255.0),
            (sky[1] + ctx.glow_col[1] * g).min(255.0),
            (sky[2] + ctx.glow_col[2] * g).min(255.0),
        ];
        if ctx.has_clouds {
            let t = ((CLOUD_BASE_M as f32 - ctx.eye_z) / d[2]).clamp(0.0, FAR_M / len);
            let dist = t * len;
            n.k = crate::math::smoothstep(0.0, 0.16, s as f64) as f32;
            n.foot = dist / ctx.f_px / s.max(0.02).sqrt();
            // Clouds are lit from the sun side: brighter toward the sun.
            let lit = 0.92 + 0.25 * g / ctx.glow_strength.max(1e-3);
            n.b = [ctx.cloud_col[0] * lit, ctx.cloud_col[1] * lit, ctx.cloud_col[2] * lit];
        }
    } else {
        let t = (-ctx.eye_z / d[2]).min(FAR_M / len);
        let dist = t * len;
        let fog = 1.0 - (-dist / ctx.visibility_m).exp();
        let haze = [ctx.haze[0] + ctx.glow_col[0] * g * 0.5, ctx.haze[1] + ctx.glow_col[1] * g * 0.5, ctx.haze[2] + ctx.glow_col[2] * g * 0.5];
        n.b = [haze[0] * fog, haze[1] * fog, haze[2] * fog];
        let graze = (-s).max(1e-3);
        n.foot = dist / ctx.f_px / graze.sqrt();
        if ctx.ground == Ground::Sea {
            // Fresnel (Schlick) mix of water body colour and reflected sky.
            let fres = 0.02 + 0.98 * (1.0 - graze).powi(5);
            let refl = lut_sky(&ctx.sky_lut, graze);
            let mut base = [0f32; 3];
            for c in 0..3 {
                base[c] = (ctx.water[c] * (1.0 - fres) + refl[c] * fres * 0.9) * (1.0 - fog);
            }
            n.a = base;
            // Glint: reflected ray (dx, dy, -dz) against the sun.
            let cos_r = (d[0] * ctx.sun[0] + d[1] * ctx.sun[1] - d[2] * ctx.sun[2]) / len;
            let ang2 = 2.0 * (1.0 - cos_r).max(0.0);
            n.k = ctx.glint_strength * (-ang2 / 0.012).exp() * (1.0 - fog);
        } else {
            n.a = [1.0 - fog, 0.0, 0.0];
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

/// Fixed-point (8 fractional bits) texel coordinates of a segment's first pixel and per-pixel step.
#[derive(Clone, Copy, Debug)]
struct Affine {
    u: i32,
    v: i32,
    du: i32,
    dv: i32,
}

/// Intersect the segment-end rays with a horizontal plane `dh` metres above the eye (negative =
/// below) and return texture coordinates stepped linearly in between. Along a segment the depth
/// changes very little, so this affine step is practically exact (it is exact for zero roll
/// through a pinhole lens); cells where it is not are handled per pixel.
#[inline]
fn plane_affine(eye_u: f64, eye_v: f64, dh: f64, n0: &Node, n1: &Node, texels_per_m: f64) -> Affine {
    let at = |n: &Node| -> (f64, f64) {
        let horiz = ((n.du * n.du + n.dv * n.dv) as f64).sqrt().max(1e-9);
        let t = (dh / n.d[2] as f64).clamp(0.0, FAR_M as f64 / horiz);
        let k = texels_per_m * 256.0;
        ((eye_u + t * n.du as f64) * k, (eye_v + t * n.dv as f64) * k)
    };
    let (u0, v0) = at(n0);
    let (u1, v1) = at(n1);
    let inv = 1.0 / GRID as f64;
    Affine { u: u0 as i64 as i32, v: v0 as i64 as i32, du: ((u1 - u0) * inv) as i32, dv: ((v1 - v0) * inv) as i32 }
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
fn sky_span(ctx: &FrameCtx, tex: &Textures, seg: &mut [u8], n0: &Node, n1: &Node) {
    if !ctx.has_clouds || (n0.k <= 0.0 && n1.k <= 0.0) {
        // Plain gradient: 16.16 fixed-point colour steps (node colours are clamped to 0..255).
        const ONE: f32 = 65536.0;
        let inv = ONE / GRID as f32;
        let mut c = [(n0.a[0] * ONE) as i32, (n0.a[1] * ONE) as i32, (n0.a[2] * ONE) as i32];
        let dc = [((n1.a[0] - n0.a[0]) * inv) as i32, ((n1.a[1] - n0.a[1]) * inv) as i32, ((n1.a[2] - n0.a[2]) * inv) as i32];
        for px in seg.chunks_exact_mut(3) {
            px[0] = (c[2] >> 16) as u8;
            px[1] = (c[1] >> 16) as u8;
            px[2] = (c[0] >> 16) as u8;
            c = [c[0] + dc[0], c[1] + dc[1], c[2] + dc[2]];
        }
        return;
    }
    let inv = 1.0 / GRID as f32;
    let mut a = n0.a;
    let da = [(n1.a[0] - a[0]) * inv, (n1.a[1] - a[1]) * inv, (n1.a[2] - a[2]) * inv];
    let level = mip_level(n0.foot.min(n1.foot) / CLOUD_TEXEL_M);
    let view = tex.clouds.view(level);
    let aff = plane_affine(ctx.cloud_eye_u, ctx.cloud_eye_v, CLOUD_BASE_M - ctx.eye_z as f64, n0, n1, 1.0 / CLOUD_TEXEL_M as f64);
    let (mut u, mut v) = (aff.u, aff.v);
    let mut k = n0.k;
    let dk = (n1.k - k) * inv;
    let b = n0.b;
    for px in seg.chunks_exact_mut(3) {
        let c = view.get(u >> 8, v >> 8) as usize;
        let al = ctx.cloud_alpha[c] * k;
        let sh = ctx.cloud_shade[c] * al;
        let ia = 1.0 - al;
        store(px, a[0] * ia + b[0] * sh, a[1] * ia + b[1] * sh, a[2] * ia + b[2] * sh);
        a = [a[0] + da[0], a[1] + da[1], a[2] + da[2]];
        u = u.wrapping_add(aff.du);
        v = v.wrapping_add(aff.dv);
        k += dk;
    }
}

/// Ground pixels of one segment (land or sea).
fn ground_span(ctx: &FrameCtx, tex: &Textures, seg: &mut [u8], n0: &Node, n1: &Node) {
    let inv = 1.0 / GRID as f32;
    let mut a = n0.a;
    let da = [(n1.a[0] - a[0]) * inv, (n1.a[1] - a[1]) * inv, (n1.a[2] - a[2]) * inv];
    let mut b = n0.b;
    let db = [(n1.b[0] - b[0]) * inv, (n1.b[1] - b[1]) * inv, (n1.b[2] - b[2]) * inv];
    let foot = n0.foot.min(n1.foot);
    let dh = -(ctx.eye_z as f64);
    if ctx.ground == Ground::Sea {
        let level = mip_level(foot / WAVE_TEXEL_M);
        let (w1, w2) = (tex.waves.view(level), tex.waves.view(level.saturating_sub(3)));
        let aff = plane_affine(ctx.eye_u, ctx.eye_v, dh, n0, n1, 1.0 / WAVE_TEXEL_M as f64);
        let (mut u, mut v) = (aff.u, aff.v);
        let mut k = n0.k;
        let dk = (n1.k - k) * inv;
        for px in seg.chunks_exact_mut(3) {
            let (ui, vi) = (u >> 8, v >> 8);
            // Long swell: the same texture 8x larger and turned 90°.
            let lum = w1.get(ui, vi) as f32 * w2.get(vi >> 3, ui >> 3) as f32 * (1.0 / (128.0 * 128.0));
            let spark = k * (0.25 + (lum - 0.9).max(0.0) * 2.5);
            store(px, a[0] * lum + b[0] + spark, a[1] * lum + b[1] + spark, a[2] * lum + b[2] + spark * 0.95);
            u = u.wrapping_add(aff.du);
            v = v.wrapping_add(aff.dv);
            a = [a[0] + da[0], a[1] + da[1], a[2] + da[2]];
            b = [b[0] + db[0], b[1] + db[1], b[2] + db[2]];
            k += dk;
        }
        return;
    }
    let level = mip_level(foot / GROUND_TEXEL_M);
    let det = tex.grass.view(level);
    let mac = tex.grass.view(level.saturating_sub(MACRO_SHIFT));
    let pal = &ctx.palette_i[level as usize];
    let aff = plane_affine(ctx.eye_u, ctx.eye_v, dh, n0, n1, 1.0 / GROUND_TEXEL_M as f64);
    let n = (seg.len() / 3) as i32;
    let (ue, ve) = (aff.u.wrapping_add(aff.du * (n - 1)), aff.v.wrapping_add(aff.dv * (n - 1)));
    // Large-scale luminance is smooth: sample it at the segment ends only and fold it together
    // with the haze attenuation into one fixed-point gain (131072 = 1.0), stepped per pixel.
    let m0 = mac.get(aff.u >> (8 + MACRO_SHIFT), aff.v >> (8 + MACRO_SHIFT)) as f32;
    let m1 = mac.get(ue >> (8 + MACRO_SHIFT), ve >> (8 + MACRO_SHIFT)) as f32;
    let m1 = m0 + (m1 - m0) * GRID as f32 / (n.max(2) - 1) as f32;
    const FIX: f32 = 65536.0;
    let g0 = n0.a[0] * m0 * (2.0 * FIX / 128.0);
    let g1 = n1.a[0] * m1 * (2.0 * FIX / 128.0);
    let mut g = g0 as i32;
    let dg = ((g1 - g0) * inv) as i32;
    let mut bb = [(b[0] * FIX) as i32, (b[1] * FIX) as i32, (b[2] * FIX) as i32];
    let dbb = [(db[0] * FIX) as i32, (db[1] * FIX) as i32, (db[2] * FIX) as i32];
    let (mut u, mut v) = (aff.u, aff.v);
    let fs = ctx.field_seed;
    let stripe_on = ctx.stripe_amp[level as usize];
    // Most segments lie inside one field: look its colour up once.
    let f0 = field_at(fs, u >> 8, v >> 8);
    let f1 = field_at(fs, ue >> 8, ve >> 8);
    let single = f0.0 == f1.0 && f0.1 == f1.1;
    for px in seg.chunks_exact_mut(3) {
        let (ui, vi) = (u >> 8, v >> 8);
        let h = if single { f0.2 } else { field_at(fs, ui, vi).2 };
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
        u = u.wrapping_add(aff.du);
        v = v.wrapping_add(aff.dv);
        g += dg;
        bb = [bb[0] + dbb[0], bb[1] + dbb[1], bb[2] + dbb[2]];
    }
}
