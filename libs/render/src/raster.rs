//! Z-buffered triangle rasterisation in distorted pixel space, plus anti-aliased wires.
//!
//! Vertices go through the lens model individually; triangles are then filled as straight-edged
//! triangles in pixel space. Meshes keep triangles small, so straight 3D lines bend correctly.
//! Sampling is at pixel centres (integer coordinates), attributes (1/z and colour) are
//! interpolated linearly in pixel space (exact for 1/z under a pinhole; the distortion error is
//! negligible for small triangles).

use crate::camera::RasterProjector;
use crate::math::{dot, norm, sub, WorldToCam, V3};
use crate::mesh::{Mesh, Tag, Vertex};

/// Near clipping plane distance in front of the camera (m).
pub(crate) const NEAR_M: f64 = 0.05;
/// Wires longer than this are split so they bend with the lens distortion (m).
const WIRE_STEP_M: f64 = 5.0;
/// Wires thinner than this fraction of a pixel are not drawn at all.
const WIRE_MIN_ALPHA: f32 = 0.04;

/// Light and atmosphere used to shade mesh vertices.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Lighting {
    /// Unit vector toward the sun (world).
    pub sun: V3,
    /// Direct sun intensity (multiplies albedo · max(0, n·sun)).
    pub sun_k: f32,
    /// Ambient from the sky dome (for an upward normal).
    pub amb_sky: f32,
    /// Ambient bounced from the ground (for a downward normal).
    pub amb_ground: f32,
    /// Haze colour (0..255 RGB) that distant objects fade to.
    pub haze: [f32; 3],
    /// Distance at which objects are ~63 % hazed (m).
    pub visibility_m: f64,
    /// Camera centre (world), for the haze distance.
    pub eye: V3,
}

impl Lighting {
    /// Shaded colour (0..255 RGB) of a vertex.
    #[inline]
    pub fn shade(&self, v: &Vertex) -> [f32; 3] {
        let nz = v.n[2] as f32;
        let amb = self.amb_sky * (0.5 + 0.5 * nz) + self.amb_ground * (0.5 - 0.5 * nz);
        let diff = (dot(v.n, self.sun) as f32).max(0.0) * self.sun_k * v.sun_vis;
        let k = (amb + diff) * 255.0;
        let fog = self.fog(norm(sub(v.p, self.eye)));
        [
            v.albedo[0] * k * (1.0 - fog) + self.haze[0] * fog,
            v.albedo[1] * k * (1.0 - fog) + self.haze[1] * fog,
            v.albedo[2] * k * (1.0 - fog) + self.haze[2] * fog,
        ]
    }

    /// Haze fraction at a distance.
    #[inline]
    pub fn fog(&self, dist_m: f64) -> f32 {
        (1.0 - (-dist_m / self.visibility_m).exp()) as f32
    }
}

/// A vertex in pixel space.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct SVert {
    pub x: f64,
    pub y: f64,
    /// 1 / depth (1/m).
    pub iz: f64,
    /// Colour 0..255 RGB.
    pub c: [f32; 3],
}

/// A vertex in camera space with its shaded colour.
#[derive(Clone, Copy, Debug, Default)]
struct CVert {
    p: V3,
    c: [f32; 3],
}

/// Whether triangles test and write the depth buffer.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum DepthMode {
    /// Normal z-buffered drawing.
    TestWrite,
    /// Painter's algorithm backdrop (hills): overwrite colour, leave depth alone.
    Backdrop,
}

/// Rasteriser state: depth buffer and per-frame scratch (all reused between frames).
pub(crate) struct Raster {
    w: usize,
    h: usize,
    proj: RasterProjector,
    /// 1/z per pixel; 0 = nothing drawn (infinitely far).
    zbuf: Vec<f32>,
    /// Region of `zbuf` written since the last clear: (x0, y0, x1, y1) inclusive.
    dirty: Option<[usize; 4]>,
    cverts: Vec<CVert>,
    sverts: Vec<SVert>,
    /// Per row: leftmost and rightmost pixel column covered by main-tower triangles (or (i32::MAX, i32::MIN)).
    pub tower_spans: Vec<(i32, i32)>,
}

impl Raster {
    pub fn new(cam: &crate::Camera) -> Raster {
        let (w, h) = (cam.width as usize, cam.height as usize);
        Raster {
            w,
            h,
            proj: RasterProjector::new(cam),
            zbuf: vec![0.0; w * h],
            dirty: None,
            cverts: Vec::new(),
            sverts: Vec::new(),
            tower_spans: vec![(i32::MAX, i32::MIN); h],
        }
    }

    /// Reset depth (only the region touched last frame) and the tower spans.
    pub fn begin_frame(&mut self) {
        if let Some([x0, y0, x1, y1]) = self.dirty.take() {
            for y in y0..=y1 {
                self.zbuf[y * self.w + x0..=y * self.w + x1].fill(0.0);
            }
        }
        self.tower_spans.fill((i32::MAX, i32::MIN));
    }

    fn mark_dirty(&mut self, x0: usize, y0: usize, x1: usize, y1: usize) {
        self.dirty = Some(match self.dirty {
            None => [x0, y0, x1, y1],
            Some(d) => [d[0].min(x0), d[1].min(y0), d[2].max(x1), d[3].max(y1)],
        });
    }

    #[inline]
    fn to_screen(&self, c: &CVert) -> SVert {
        let p = self.proj.project(c.p);
        SVert {
            x: p[0],
            y: p[1],
            iz: 1.0 / c.p[2],
            c: c.c,
        }
    }

    /// Shade, transform, clip and rasterise all triangles of `mesh`, then its wires.
    pub fn draw_mesh(
        &mut self,
        out: &mut [u8],
        mesh: &Mesh,
        w2c: &WorldToCam,
        light: &Lighting,
        mode: DepthMode,
    ) {
        self.cverts.clear();
        self.sverts.clear();
        for v in &mesh.verts {
            let cv = CVert {
                p: w2c.point(v.p),
                c: light.shade(v),
            };
            self.cverts.push(cv);
            let sv = if cv.p[2] > NEAR_M {
                self.to_screen(&cv)
            } else {
                SVert::default()
            };
            self.sverts.push(sv);
        }
        for t in &mesh.tris {
            let [a, b, c] = t.v.map(|i| i as usize);
            let (za, zb, zc) = (
                self.cverts[a].p[2],
                self.cverts[b].p[2],
                self.cverts[c].p[2],
            );
            if za > NEAR_M && zb > NEAR_M && zc > NEAR_M {
                let (sa, sb, sc) = (self.sverts[a], self.sverts[b], self.sverts[c]);
                self.tri(out, &sa, &sb, &sc, mode, t.tag);
            } else if za > NEAR_M || zb > NEAR_M || zc > NEAR_M {
                self.clipped_tri(
                    out,
                    [self.cverts[a], self.cverts[b], self.cverts[c]],
                    mode,
                    t.tag,
                );
            }
        }
        for wire in &mesh.wires {
            self.draw_wire(out, wire, w2c, light);
        }
    }

    /// Sutherland–Hodgman clip of one triangle against the near plane, then rasterise the pieces.
    fn clipped_tri(&mut self, out: &mut [u8], v: [CVert; 3], mode: DepthMode, tag: Tag) {
        let mut poly = [CVert::default(); 4];
        let mut n = 0;
        for i in 0..3 {
            let (p, q) = (v[i], v[(i + 1) % 3]);
            let (pin, qin) = (p.p[2] > NEAR_M, q.p[2] > NEAR_M);
            if pin {
                poly[n] = p;
                n += 1;
            }
            if pin != qin {
                let t = (NEAR_M - p.p[2]) / (q.p[2] - p.p[2]);
                let tf = t as f32;
                poly[n] = CVert {
                    p: crate::math::lerp3(p.p, q.p, t),
                    c: [
                        p.c[0] + (q.c[0] - p.c[0]) * tf,
                        p.c[1] + (q.c[1] - p.c[1]) * tf,
                        p.c[2] + (q.c[2] - p.c[2]) * tf,
                    ],
                };
                n += 1;
            }
        }
        if n < 3 {
            return;
        }
        let s: [SVert; 4] = [0, 1, 2, 3].map(|i| {
            if i < n {
                self.to_screen(&poly[i])
            } else {
                SVert::default()
            }
        });
        self.tri(out, &s[0], &s[1], &s[2], mode, tag);
        if n == 4 {
            self.tri(out, &s[0], &s[2], &s[3], mode, tag);
        }
    }

    /// Fill one triangle (back faces culled). Mesh triangles are wound counter-clockwise seen
    /// from outside (right-handed normal = outward). The camera frame is right-handed with
    /// y down, so a face turned toward the camera has a negative signed area
    /// `(b - a) × (c - a)` in pixel space; the lens map is monotonic, so distortion keeps it.
    fn tri(&mut self, out: &mut [u8], a: &SVert, b: &SVert, c: &SVert, mode: DepthMode, tag: Tag) {
        let area0 = (b.x - a.x) * (c.y - a.y) - (c.x - a.x) * (b.y - a.y);
        if !(area0 < 0.0) || !area0.is_finite() {
            return; // back-facing, degenerate or NaN
        }
        // Swap to positive orientation: interior = all edge functions >= 0.
        let (a, b, c) = (a, c, b);
        let area = -area0;
        if area < 1e-9 {
            return;
        }
        let (w, h) = (self.w as f64, self.h as f64);
        // Clamp before converting so huge (off-screen) coordinates stay in range.
        let ymin = ceil_i(a.y.min(b.y).min(c.y).max(-1.0)).max(0);
        let ymax = floor_i(a.y.max(b.y).max(c.y).min(h)).min(self.h as i64 - 1);
        let xmin = ceil_i(a.x.min(b.x).min(c.x).max(-1.0)).max(0) as f64;
        let xmax = floor_i(a.x.max(b.x).max(c.x).min(w)).min(self.w as i64 - 1) as f64;
        if ymin > ymax || xmin > xmax {
            return;
        }
        // Attribute planes f(x, y) = f_a + dfdx (x - a.x) + dfdy (y - a.y).
        let (e1x, e1y, e2x, e2y) = (b.x - a.x, b.y - a.y, c.x - a.x, c.y - a.y);
        let grad = |fa: f64, fb: f64, fc: f64| -> (f64, f64) {
            let (d1, d2) = (fb - fa, fc - fa);
            ((d1 * e2y - d2 * e1y) / area, (e1x * d2 - e2x * d1) / area)
        };
        let (izx, izy) = grad(a.iz, b.iz, c.iz);
        let mut cg = [(0.0, 0.0); 3];
        for k in 0..3 {
            cg[k] = grad(a.c[k] as f64, b.c[k] as f64, c.c[k] as f64);
        }
        // Per edge p->q: interior is `dy * x <= (q.x - p.x)(y - p.y) + dy * p.x`, i.e. an upper
        // bound on x when dy > 0 and a lower bound when dy < 0, linear in y.
        let mut lower: [(f64, f64); 3] = [(f64::NEG_INFINITY, 0.0); 3];
        let mut upper: [(f64, f64); 3] = [(f64::INFINITY, 0.0); 3];
        let mut horizontal_reject: [(f64, f64, f64); 3] = [(0.0, 0.0, 0.0); 3];
        let (mut nl, mut nu, mut nh) = (0, 0, 0);
        for (p, q) in [(a, b), (b, c), (c, a)] {
            let dy = q.y - p.y;
            if dy != 0.0 {
                let slope = (q.x - p.x) / dy;
                // bound(y) = p.x + slope * (y - p.y)
                let e = (p.x - slope * p.y, slope);
                if dy > 0.0 {
                    upper[nu] = e;
                    nu += 1;
                } else {
                    lower[nl] = e;
                    nl += 1;
                }
            } else {
                // Horizontal edge: all-or-nothing per row, k = (q.x - p.x)(y - p.y) >= 0.
                horizontal_reject[nh] = (q.x - p.x, p.y, 0.0);
                nh += 1;
            }
        }
        let (y0, y1) = (ymin as usize, ymax as usize);
        let is_tower = tag == Tag::Tower;
        let mut touched: Option<(usize, usize)> = None;
        for y in y0..=y1 {
            let yf = y as f64;
            let (mut lo, mut hi) = (xmin, xmax);
            for e in &lower[..nl] {
                lo = lo.max(e.0 + e.1 * yf);
            }
            for e in &upper[..nu] {
                hi = hi.min(e.0 + e.1 * yf);
            }
            if horizontal_reject[..nh]
                .iter()
                .any(|e| e.0 * (yf - e.1) < 0.0)
            {
                continue;
            }
            // A tiny tolerance makes shared edges overlap instead of leaving cracks.
            if !(lo - 1e-7 <= hi + 1e-7) {
                continue;
            }
            let (xl, xr) = (ceil_i(lo - 1e-7), floor_i(hi + 1e-7));
            if xl > xr {
                continue;
            }
            let (xl, xr) = (xl as usize, xr as usize);
            touched = Some(match touched {
                None => (xl, xr),
                Some((l, r)) => (l.min(xl), r.max(xr)),
            });
            if is_tower {
                let s = &mut self.tower_spans[y];
                s.0 = s.0.min(xl as i32);
                s.1 = s.1.max(xr as i32);
            }
            let (dx0, dy0) = (xl as f64 - a.x, yf - a.y);
            let mut iz = (a.iz + izx * dx0 + izy * dy0) as f32;
            let diz = izx as f32;
            let mut col = [0f32; 3];
            let mut dcol = [0f32; 3];
            for k in 0..3 {
                col[k] = (a.c[k] as f64 + cg[k].0 * dx0 + cg[k].1 * dy0) as f32;
                dcol[k] = cg[k].0 as f32;
            }
            let row = y * self.w;
            let zrow = &mut self.zbuf[row + xl..=row + xr];
            let orow = &mut out[(row + xl) * 3..(row + xr + 1) * 3];
            match mode {
                DepthMode::TestWrite => {
                    for (z, px) in zrow.iter_mut().zip(orow.chunks_exact_mut(3)) {
                        if iz > *z {
                            *z = iz;
                            px[0] = col[2] as u8;
                            px[1] = col[1] as u8;
                            px[2] = col[0] as u8;
                        }
                        iz += diz;
                        col[0] += dcol[0];
                        col[1] += dcol[1];
                        col[2] += dcol[2];
                    }
                }
                DepthMode::Backdrop => {
                    for px in orow.chunks_exact_mut(3) {
                        px[0] = col[2] as u8;
                        px[1] = col[1] as u8;
                        px[2] = col[0] as u8;
                        col[0] += dcol[0];
                        col[1] += dcol[1];
                        col[2] += dcol[2];
                    }
                }
            }
        }
        if mode == DepthMode::TestWrite {
            if let Some((l, r)) = touched {
                self.mark_dirty(l, y0, r, y1);
            }
        }
    }

    /// Draw a wire as an anti-aliased line, depth-tested against the z-buffer (no depth write).
    fn draw_wire(
        &mut self,
        out: &mut [u8],
        wire: &crate::mesh::Wire,
        w2c: &WorldToCam,
        light: &Lighting,
    ) {
        let len = norm(sub(wire.b, wire.a));
        let pieces = ((len / WIRE_STEP_M).ceil() as usize).max(1);
        // Wires are lit like a thin cylinder: mostly ambient plus some sun.
        let fake = Vertex {
            p: wire.a,
            n: [0.0, 0.0, 1.0],
            albedo: wire.albedo,
            sun_vis: 0.35,
        };
        let col = light.shade(&fake);
        for i in 0..pieces {
            let pa = crate::math::lerp3(wire.a, wire.b, i as f64 / pieces as f64);
            let pb = crate::math::lerp3(wire.a, wire.b, (i + 1) as f64 / pieces as f64);
            let (mut ca, mut cb) = (w2c.point(pa), w2c.point(pb));
            if ca[2] <= NEAR_M && cb[2] <= NEAR_M {
                continue;
            }
            if ca[2] <= NEAR_M || cb[2] <= NEAR_M {
                let t = (NEAR_M - ca[2]) / (cb[2] - ca[2]);
                let m = crate::math::lerp3(ca, cb, t);
                if ca[2] <= NEAR_M {
                    ca = m;
                } else {
                    cb = m;
                }
            }
            let (sa, sb) = (self.proj.project(ca), self.proj.project(cb));
            let zmid = 0.5 * (ca[2] + cb[2]);
            let fx = (self.proj.fx()).max(1.0);
            let width_px = (wire.width_m * fx / zmid) as f32;
            self.line(out, sa, sb, 1.0 / ca[2], 1.0 / cb[2], width_px, col);
        }
    }

    /// Anti-aliased line of pixel width `width_px` (sub-pixel widths become partial opacity).
    #[allow(clippy::too_many_arguments)]
    fn line(
        &mut self,
        out: &mut [u8],
        a: [f64; 2],
        b: [f64; 2],
        iza: f64,
        izb: f64,
        width_px: f32,
        col: [f32; 3],
    ) {
        let alpha_w = width_px.min(1.0);
        if alpha_w < WIRE_MIN_ALPHA
            || !(a[0].is_finite() && b[0].is_finite() && a[1].is_finite() && b[1].is_finite())
        {
            return;
        }
        let (w, h) = (self.w as f64, self.h as f64);
        // Reject lines entirely off-screen.
        if (a[0] < -1.0 && b[0] < -1.0)
            || (a[0] > w && b[0] > w)
            || (a[1] < -1.0 && b[1] < -1.0)
            || (a[1] > h && b[1] > h)
        {
            return;
        }
        let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
        let steep = dy.abs() > dx.abs();
        let (major_len, ma0, mi0, dmi, dma) = if steep {
            (dy.abs(), a[1], a[0], dx / dy.abs().max(1e-12), dy.signum())
        } else {
            (dx.abs(), a[0], a[1], dy / dx.abs().max(1e-12), dx.signum())
        };
        // Limit work for absurdly long projected lines (vertices far outside the image).
        let steps = major_len.ceil().min(4.0 * (w + h)) as usize;
        let half = (width_px.max(1.0) / 2.0) as f64;
        for s in 0..=steps {
            let t = if major_len > 0.0 {
                (s as f64).min(major_len)
            } else {
                0.0
            };
            let ma = ma0 + dma * t;
            let mi = mi0 + dmi * t;
            let frac_along = if major_len > 0.0 { t / major_len } else { 0.0 };
            let iz = (iza + (izb - iza) * frac_along) as f32;
            let mai = ma.round();
            let (k0, k1) = (
                (mi - half - 0.5).ceil() as i64,
                (mi + half + 0.5).floor() as i64,
            );
            for k in k0..=k1 {
                // Coverage of pixel k by the interval [mi - half, mi + half].
                let cov = ((k as f64 + 0.5).min(mi + half) - (k as f64 - 0.5).max(mi - half))
                    .clamp(0.0, 1.0) as f32;
                let alpha = cov * alpha_w;
                if alpha <= 0.0 {
                    continue;
                }
                let (px, py) = if steep {
                    (k as f64, mai)
                } else {
                    (mai, k as f64)
                };
                if px < 0.0 || py < 0.0 || px >= w || py >= h {
                    continue;
                }
                let idx = py as usize * self.w + px as usize;
                if iz <= self.zbuf[idx] {
                    continue;
                }
                let o = &mut out[idx * 3..idx * 3 + 3];
                for c in 0..3 {
                    let dst = o[2 - c] as f32;
                    o[2 - c] = (dst + (col[c] - dst) * alpha) as u8;
                }
            }
        }
    }
}

/// `floor` without a libm call (the baseline x86-64 target has no rounding instruction).
/// Inputs are pre-clamped to a few thousand pixels, far inside i64.
#[inline(always)]
fn floor_i(x: f64) -> i64 {
    let i = x as i64;
    if (i as f64) > x {
        i - 1
    } else {
        i
    }
}

/// `ceil` without a libm call; see [`floor_i`].
#[inline(always)]
fn ceil_i(x: f64) -> i64 {
    let i = x as i64;
    if (i as f64) < x {
        i + 1
    } else {
        i
    }
}
