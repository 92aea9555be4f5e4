//! Procedural tileable textures (value-noise fBm) with box-filtered mip levels.
//!
//! Built once per [`crate::Renderer`]; scenes pick different placements (offsets, rotation,
//! palette, cloud coverage) from their seed, so switching seeds costs nothing.

use crate::math::hash64;

/// Edge length of every texture's top mip level (texels, power of two).
pub(crate) const TEX_SIZE: usize = 512;
/// log2 of [`TEX_SIZE`].
pub(crate) const TEX_LOG2: u32 = 9;
/// Number of mip levels (512 down to 1).
pub(crate) const TEX_LEVELS: usize = TEX_LOG2 as usize + 1;

/// A square luminance/density texture with mips; values 0..255.
pub(crate) struct MipTex {
    /// Level `l` has edge `TEX_SIZE >> l`.
    levels: Vec<Vec<u8>>,
}

impl MipTex {
    fn from_level0(data: Vec<u8>) -> MipTex {
        // Every level is stored with the level-0 row stride so texel addressing needs only
        // constant shifts: index = (v & mask) << TEX_LOG2 | (u & mask).
        let mut levels = vec![data];
        let mut size = TEX_SIZE;
        while size > 1 {
            let prev = &levels[levels.len() - 1];
            let ns = size / 2;
            let mut next = vec![0u8; ns * TEX_SIZE];
            for y in 0..ns {
                for x in 0..ns {
                    let at = |yy: usize, xx: usize| prev[yy * TEX_SIZE + xx] as u32;
                    let s = at(2 * y, 2 * x)
                        + at(2 * y, 2 * x + 1)
                        + at(2 * y + 1, 2 * x)
                        + at(2 * y + 1, 2 * x + 1);
                    next[y * TEX_SIZE + x] = ((s + 2) / 4) as u8;
                }
            }
            levels.push(next);
            size = ns;
        }
        MipTex { levels }
    }

    /// A view of one mip level, addressed in that level's own texel units (wrapping).
    #[inline(always)]
    pub fn view(&self, level: u32) -> TexView<'_> {
        TexView {
            data: &self.levels[level as usize],
            mask: (TEX_SIZE as i32 >> level) - 1,
        }
    }
}

/// One mip level of a [`MipTex`].
#[derive(Clone, Copy)]
pub(crate) struct TexView<'a> {
    data: &'a [u8],
    mask: i32,
}

impl TexView<'_> {
    /// Texel at integer coordinates of this level (wrapping).
    #[inline(always)]
    pub fn get(&self, u: i32, v: i32) -> u8 {
        let idx = (((v & self.mask) << TEX_LOG2) | (u & self.mask)) as usize;
        self.data[idx]
    }
}

/// Tileable value noise on a `size x size` grid with `cx x cy` lattice cells, values in [0, 1].
fn value_noise_into(acc: &mut [f32], size: usize, cx: usize, cy: usize, seed: u64, amp: f32) {
    let lattice: Vec<f32> = (0..cx * cy)
        .map(|i| {
            (hash64(seed ^ (i as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15)) >> 40) as f32
                / (1u64 << 24) as f32
        })
        .collect();
    let smooth = |t: f32| t * t * (3.0 - 2.0 * t);
    for y in 0..size {
        let fy = y as f32 * cy as f32 / size as f32;
        let y0 = fy as usize % cy;
        let y1 = (y0 + 1) % cy;
        let ty = smooth(fy - fy.floor());
        for x in 0..size {
            let fx = x as f32 * cx as f32 / size as f32;
            let x0 = fx as usize % cx;
            let x1 = (x0 + 1) % cx;
            let tx = smooth(fx - fx.floor());
            let a = lattice[y0 * cx + x0] + (lattice[y0 * cx + x1] - lattice[y0 * cx + x0]) * tx;
            let b = lattice[y1 * cx + x0] + (lattice[y1 * cx + x1] - lattice[y1 * cx + x0]) * tx;
            acc[y * size + x] += amp * (a + (b - a) * ty);
        }
    }
}

/// Fractal sum of value noise, normalised to [0, 1] by its actual range.
/// `aniso` stretches the features along x (waves).
fn fbm(base_cells: usize, octaves: usize, gain: f32, aniso: usize, seed: u64) -> Vec<f32> {
    let mut acc = vec![0f32; TEX_SIZE * TEX_SIZE];
    let mut amp = 1.0;
    let mut cells = base_cells;
    for o in 0..octaves {
        let cx = (cells / aniso).max(1);
        value_noise_into(
            &mut acc,
            TEX_SIZE,
            cx,
            cells.min(TEX_SIZE),
            hash64(seed.wrapping_add(o as u64)),
            amp,
        );
        amp *= gain;
        cells = (cells * 2).min(TEX_SIZE);
    }
    let (mn, mx) = acc
        .iter()
        .fold((f32::MAX, f32::MIN), |(a, b), &v| (a.min(v), b.max(v)));
    let inv = 1.0 / (mx - mn).max(1e-6);
    acc.iter_mut().for_each(|v| *v = (*v - mn) * inv);
    acc
}

/// All procedural textures of a renderer.
pub(crate) struct Textures {
    /// Grass/field detail luminance, 128 = 1.0.
    pub grass: MipTex,
    /// Sea wave luminance, 128 = 1.0.
    pub waves: MipTex,
    /// Cloud density 0..255.
    pub clouds: MipTex,
    /// Shrubland detail luminance (dark bushes 1–3 m across on light soil), 128 = 1.0.
    pub shrubs: MipTex,
}

/// Noise level above which the shrub texture is bush (about half the ground is covered).
const SHRUB_COVER_LEVEL: f32 = 0.5;
/// Width of the bushes' soft rim, in noise units.
const SHRUB_RIM: f32 = 0.08;

/// Fixed seed of the texture set: scenes vary placement, not the textures themselves.
const TEXTURE_SEED: u64 = 0x7E47_0E5E_ED00_0001;

impl Textures {
    pub fn new() -> Textures {
        let g = fbm(8, 7, 0.55, 1, TEXTURE_SEED);
        // Luminance 0.70 .. 1.30 with mean ~1.
        let grass = MipTex::from_level0(
            g.iter()
                .map(|&v| (128.0 * (0.70 + 0.60 * v)) as u8)
                .collect(),
        );
        let w = fbm(16, 6, 0.6, 4, TEXTURE_SEED ^ 0x5EA);
        let waves = MipTex::from_level0(
            w.iter()
                .map(|&v| (128.0 * (0.62 + 0.76 * v * v * 1.2).min(1.95)) as u8)
                .collect(),
        );
        let c = fbm(4, 8, 0.55, 1, TEXTURE_SEED ^ 0xC10D);
        let clouds = MipTex::from_level0(c.iter().map(|&v| (v * 255.0) as u8).collect());
        // Bushes: the top of high-frequency noise, with a soft rim (a texel is 0.5 m, so the
        // 128-cell base lattice gives bushes ~2 m apart), over coarser noise that thins and
        // thickens them. Soil 1.3, bush 0.55 of the field colour.
        let b = fbm(128, 2, 0.5, 1, TEXTURE_SEED ^ 0xB05);
        let density = fbm(16, 3, 0.5, 1, TEXTURE_SEED ^ 0xB06);
        let bush = |v: f32, d: f32| {
            ((v + 0.3 * (d - 0.5) - SHRUB_COVER_LEVEL) / SHRUB_RIM + 0.5).clamp(0.0, 1.0)
        };
        let shrubs = MipTex::from_level0(
            b.iter()
                .zip(&density)
                .map(|(&v, &d)| (128.0 * (1.3 - 0.75 * bush(v, d))) as u8)
                .collect(),
        );
        Textures {
            grass,
            waves,
            clouds,
            shrubs,
        }
    }
}

/// Mip level for a footprint of `foot` texels per pixel: floor(log2(foot)) clamped, from the f32
/// exponent bits (cheap enough to call per 8-pixel segment).
#[inline(always)]
pub(crate) fn mip_level(foot_texels: f32) -> u32 {
    if !(foot_texels > 1.0) {
        return 0;
    }
    let e = ((foot_texels.to_bits() >> 23) & 0xff) as i32 - 127;
    (e.max(0) as u32).min(TEX_LEVELS as u32 - 1)
}
