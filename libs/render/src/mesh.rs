//! Triangle meshes of the turbine, distractors and hills, built in world coordinates.
//!
//! Meshes are rebuilt every frame into reused vectors (no per-frame allocation once the vectors
//! have grown). Long edges are subdivided into pieces of a few metres so that straight lines bend
//! correctly when vertices are projected through the lens distortion and triangles are then
//! rasterised in distorted pixel space.

use crate::math::{add, cross, deg, dot, lerp3, normalize, scale, sub, Rng, V3};
use crate::scene::{NacelleSize, Scene, NACELLE_HEIGHT_M, NACELLE_WIDTH_M, SPINNER_RADIUS_M};

/// Turbine paint (RAL 7035-like light grey), linear 0..1 albedo per RGB channel.
pub(crate) const TURBINE_ALBEDO: [f32; 3] = [0.86, 0.87, 0.86];
/// Galvanised steel of masts and pylons.
pub(crate) const STEEL_ALBEDO: [f32; 3] = [0.55, 0.57, 0.58];
/// Conductor cables (weathered aluminium, looks dark against the sky).
pub(crate) const CABLE_ALBEDO: [f32; 3] = [0.30, 0.31, 0.32];
/// Weathered concrete of a chimney.
pub(crate) const CONCRETE_ALBEDO: [f32; 3] = [0.62, 0.60, 0.57];

/// Tower ring spacing along the height (m) for the main turbine.
const TOWER_RING_STEP_M: f64 = 3.0;
/// Finer ring spacing near the top so the nacelle shadow edge is crisp (m).
const TOWER_TOP_RING_STEP_M: f64 = 0.35;
/// Height band below the tower top that gets the fine rings (m).
const TOWER_TOP_FINE_ZONE_M: f64 = 10.0;
/// Segments around the tower circumference (silhouette width error < 0.4 %).
const TOWER_SEGMENTS: usize = 40;
/// Maximum length of a nacelle face subdivision (m).
const NACELLE_STEP_M: f64 = 2.0;
/// Nacelle edge chamfer (m).
const NACELLE_CHAMFER_M: f64 = 0.45;
/// Spinner cylinder length behind the blade-root plane (m).
const SPINNER_BACK_M: f64 = 1.25;
/// Segments around the spinner.
const SPINNER_SEGMENTS: usize = 24;
/// Blade root (circular) diameter (m) for a 33.5 m blade; scales with blade length.
const BLADE_ROOT_DIAMETER_M: f64 = 1.9;
/// Maximum chord (m) for a 33.5 m blade.
const BLADE_MAX_CHORD_M: f64 = 2.9;
/// Chord near the tip (m) for a 33.5 m blade.
const BLADE_TIP_CHORD_M: f64 = 0.55;
/// How the root diameter grows with blade length: `(len / ref)^this`. Roots grow slower than
/// the blade (about 1.9 m at 33.5 m, 2.0 m at 44 m, 2.3–2.5 m at 55 m blades in published blade
/// data), so long blades do not end in roots as wide as the spinner.
const BLADE_ROOT_SCALING_EXP: f64 = 0.5;
/// How the chords grow with blade length: `(len / ref)^this` (about 2.9 m at 33.5 m, 3.5 m at
/// 44 m, 4.0–4.3 m at 55 m).
const BLADE_CHORD_SCALING_EXP: f64 = 0.75;
/// Reference blade length the chord constants refer to (m).
const BLADE_REF_LENGTH_M: f64 = 33.5;
/// Radius (fraction of blade length) of maximum chord.
const BLADE_MAX_CHORD_FRAC: f64 = 0.22;
/// Radius where the blade starts, inside the spinner (m).
const BLADE_ROOT_START_M: f64 = 1.0;
/// Radius where the circular root starts morphing into the airfoil (m).
const BLADE_ROOT_CYLINDER_END_M: f64 = 2.6;
/// Aerodynamic twist at max chord (degrees), falling to 0 at the tip.
const BLADE_TWIST_DEG: f64 = 13.0;
/// Pitch axis position from the leading edge (fraction of chord).
const BLADE_PITCH_AXIS_FRAC: f64 = 0.3;
/// Station spacing along the outer blade (m).
const BLADE_STATION_STEP_M: f64 = 2.4;
/// Points around each blade cross-section (main turbine).
const BLADE_SECTION_POINTS: usize = 16;

/// Triangle tag: which object a triangle belongs to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Tag {
    /// The main turbine's tower (its pixel spans give the tower-width truth).
    Tower,
    /// Anything else.
    Other,
}

/// One mesh vertex in world coordinates.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Vertex {
    pub p: V3,
    /// Unit outward normal (used for shading and for fixing the winding).
    pub n: V3,
    pub albedo: [f32; 3],
    /// 1 = fully sunlit, 0 = in the nacelle's shadow.
    pub sun_vis: f32,
}

/// One triangle: vertex indices (wound so that the geometric normal agrees with the vertex normals).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Tri {
    pub v: [u32; 3],
    pub tag: Tag,
}

/// A thin straight wire segment (cables, lattice members) drawn as an anti-aliased line.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Wire {
    pub a: V3,
    pub b: V3,
    /// Physical thickness (m): sets the line's opacity when thinner than a pixel.
    pub width_m: f64,
    pub albedo: [f32; 3],
}

/// A reusable triangle list plus wires.
#[derive(Default, Debug)]
pub(crate) struct Mesh {
    pub verts: Vec<Vertex>,
    pub tris: Vec<Tri>,
    pub wires: Vec<Wire>,
}

impl Mesh {
    pub fn clear(&mut self) {
        self.verts.clear();
        self.tris.clear();
        self.wires.clear();
    }

    fn vert(&mut self, p: V3, n: V3, albedo: [f32; 3]) -> u32 {
        self.verts.push(Vertex {
            p,
            n,
            albedo,
            sun_vis: 1.0,
        });
        (self.verts.len() - 1) as u32
    }

    /// Add a triangle, flipping it if needed so its winding agrees with the vertex normals.
    fn tri(&mut self, a: u32, b: u32, c: u32, tag: Tag) {
        let (pa, pb, pc) = (
            self.verts[a as usize].p,
            self.verts[b as usize].p,
            self.verts[c as usize].p,
        );
        let g = cross(sub(pb, pa), sub(pc, pa));
        let n = add(
            add(self.verts[a as usize].n, self.verts[b as usize].n),
            self.verts[c as usize].n,
        );
        if dot(g, n) >= 0.0 {
            self.tris.push(Tri { v: [a, b, c], tag });
        } else {
            self.tris.push(Tri { v: [a, c, b], tag });
        }
    }

    fn quad(&mut self, a: u32, b: u32, c: u32, d: u32, tag: Tag) {
        self.tri(a, b, c, tag);
        self.tri(a, c, d, tag);
    }

    /// Connect two rings of equal length (closed loops) with quads.
    fn stitch_rings(&mut self, r0: u32, r1: u32, n: usize, tag: Tag) {
        for i in 0..n as u32 {
            let j = (i + 1) % n as u32;
            self.quad(r0 + i, r0 + j, r1 + j, r1 + i, tag);
        }
    }

    /// A flat quad face subdivided into an `nu x nv` grid (for distortion-correct bending).
    fn flat_face(&mut self, o: V3, eu: V3, ev: V3, n: V3, albedo: [f32; 3], tag: Tag) {
        let nu = ((crate::math::norm(eu) / NACELLE_STEP_M).ceil() as usize).max(1);
        let nv = ((crate::math::norm(ev) / NACELLE_STEP_M).ceil() as usize).max(1);
        let base = self.verts.len() as u32;
        for j in 0..=nv {
            for i in 0..=nu {
                let p = add(
                    o,
                    add(
                        scale(eu, i as f64 / nu as f64),
                        scale(ev, j as f64 / nv as f64),
                    ),
                );
                self.vert(p, n, albedo);
            }
        }
        let stride = (nu + 1) as u32;
        for j in 0..nv as u32 {
            for i in 0..nu as u32 {
                let a = base + j * stride + i;
                self.quad(a, a + 1, a + 1 + stride, a + stride, tag);
            }
        }
    }
}

/// Level of detail of a turbine model.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Detail {
    /// The main turbine.
    High,
    /// A turbine hundreds of metres away.
    Low,
}

/// Geometry of one turbine to build.
#[derive(Clone, Copy, Debug)]
pub(crate) struct TurbineSpec {
    /// Tower base centre, world (m).
    pub base: V3,
    pub hub_height_m: f64,
    pub tower_base_d_m: f64,
    pub tower_top_d_m: f64,
    pub blade_length_m: f64,
    /// Horizontal distance from the tower axis to the blade-root plane (m).
    pub hub_overhang_m: f64,
    /// Spinner radius at the blade-root plane (m); the nose length scales with it.
    pub spinner_radius_m: f64,
    /// The nacelle body.
    pub nacelle: NacelleSize,
    pub rotor_angle_deg: f64,
    pub nacelle_yaw_deg: f64,
    pub blade_pitch_deg: f64,
    pub detail: Detail,
    /// Sun direction for the nacelle shadow on the tower (None = no shadow).
    pub shadow_sun: Option<V3>,
}

impl TurbineSpec {
    /// The main turbine of a scene.
    pub fn main(scene: &Scene) -> TurbineSpec {
        TurbineSpec {
            base: [0.0, 0.0, 0.0],
            hub_height_m: scene.hub_height_m,
            tower_base_d_m: scene.tower_base_diameter_m,
            tower_top_d_m: scene.tower_top_diameter_m,
            blade_length_m: scene.blade_length_m,
            hub_overhang_m: scene.hub_overhang_m,
            spinner_radius_m: scene.spinner_diameter_m / 2.0,
            nacelle: scene.nacelle(),
            rotor_angle_deg: scene.rotor_angle_deg,
            nacelle_yaw_deg: scene.nacelle_yaw_deg,
            blade_pitch_deg: scene.blade_pitch_deg,
            detail: Detail::High,
            shadow_sun: if scene.nacelle_shadow {
                Some(scene.sun_dir())
            } else {
                None
            },
        }
    }
}

/// Local turbine frame: x = rotor axis (upwind), y = turbine's left, z = up, origin tower base.
struct Frame {
    o: V3,
    x: V3,
    y: V3,
}

impl Frame {
    fn p(&self, l: V3) -> V3 {
        add(
            self.o,
            add(
                scale(self.x, l[0]),
                add(scale(self.y, l[1]), [0.0, 0.0, l[2]]),
            ),
        )
    }
    fn d(&self, l: V3) -> V3 {
        add(
            scale(self.x, l[0]),
            add(scale(self.y, l[1]), [0.0, 0.0, l[2]]),
        )
    }
    fn to_local_dir(&self, w: V3) -> V3 {
        [dot(w, self.x), dot(w, self.y), w[2]]
    }
}

/// Ray/axis-aligned-box test in the local frame: does the ray from `p` along `d` hit the box?
fn ray_hits_box(p: V3, d: V3, lo: V3, hi: V3) -> bool {
    let (mut t0, mut t1) = (1e-6f64, f64::INFINITY);
    for k in 0..3 {
        if d[k].abs() < 1e-12 {
            if p[k] < lo[k] || p[k] > hi[k] {
                return false;
            }
        } else {
            let (a, b) = ((lo[k] - p[k]) / d[k], (hi[k] - p[k]) / d[k]);
            let (a, b) = if a < b { (a, b) } else { (b, a) };
            t0 = t0.max(a);
            t1 = t1.min(b);
            if t0 > t1 {
                return false;
            }
        }
    }
    true
}

/// The nacelle body of a turbine in its local frame (m): its front face `front_behind_hub_m`
/// behind the blade-root plane.
struct NacelleBox {
    front_x: f64,
    length: f64,
    height: f64,
    width: f64,
}

impl NacelleBox {
    fn of(s: &TurbineSpec) -> NacelleBox {
        let n = s.nacelle;
        NacelleBox {
            front_x: s.hub_overhang_m - n.front_behind_hub_m,
            length: n.length_m,
            height: n.height_m,
            width: n.width_m,
        }
    }
}

/// Append a complete turbine (tower, nacelle, spinner, three blades) to `mesh`.
pub(crate) fn build_turbine(mesh: &mut Mesh, s: &TurbineSpec) {
    let yaw = deg(s.nacelle_yaw_deg);
    let f = Frame {
        o: s.base,
        x: [yaw.cos(), -yaw.sin(), 0.0],
        y: [yaw.sin(), yaw.cos(), 0.0],
    };
    let high = s.detail == Detail::High;
    let tag_tower = if high { Tag::Tower } else { Tag::Other };
    let alb = TURBINE_ALBEDO;
    let hub_z = s.hub_height_m;
    let nacelle = NacelleBox::of(s);
    let top_z = hub_z - nacelle.height / 2.0;

    // --- Tower: truncated cone, rings every few metres, fine rings under the nacelle.
    let segs = if high { TOWER_SEGMENTS } else { 12 };
    let (rb, rt) = (s.tower_base_d_m / 2.0, s.tower_top_d_m / 2.0);
    let slope = (rt - rb) / top_z;
    let nac_lo = [
        nacelle.front_x - nacelle.length,
        -nacelle.width / 2.0,
        hub_z - nacelle.height / 2.0,
    ];
    let nac_hi = [
        nacelle.front_x,
        nacelle.width / 2.0,
        hub_z + nacelle.height / 2.0,
    ];
    let sun_local = s.shadow_sun.map(|w| f.to_local_dir(w));
    let mut z = 0.0;
    let mut prev_ring: Option<u32> = None;
    loop {
        let ring = mesh.verts.len() as u32;
        let r = rb + slope * z;
        for i in 0..segs {
            let a = std::f64::consts::TAU * i as f64 / segs as f64;
            let (c, sn) = (a.cos(), a.sin());
            let local = [r * c, r * sn, z];
            let n_local = normalize([c, sn, -slope]);
            let vi = mesh.vert(f.p(local), f.d(n_local), alb);
            if let Some(sl) = sun_local {
                if sl[2] > 0.0 && ray_hits_box(local, sl, nac_lo, nac_hi) {
                    mesh.verts[vi as usize].sun_vis = 0.0;
                }
            }
        }
        if let Some(p) = prev_ring {
            mesh.stitch_rings(p, ring, segs, tag_tower);
        }
        prev_ring = Some(ring);
        if z >= top_z {
            break;
        }
        let step = if !high {
            10.0
        } else if z >= top_z - TOWER_TOP_FINE_ZONE_M && s.shadow_sun.is_some() {
            TOWER_TOP_RING_STEP_M
        } else {
            TOWER_RING_STEP_M
        };
        z = (z + step).min(top_z);
        if top_z - z < 0.05 {
            z = top_z;
        }
    }

    // --- Nacelle: chamfered box along the rotor axis, each face flat-shaded.
    let (hw, hh, c) = (
        nacelle.width / 2.0,
        nacelle.height / 2.0,
        // The default body's chamfer, scaled with the smaller of its height and width.
        NACELLE_CHAMFER_M
            * (nacelle.height / NACELLE_HEIGHT_M).min(nacelle.width / NACELLE_WIDTH_M),
    );
    // Cross-section outline (y, z offsets from the axis), counter-clockwise seen from the front.
    let outline: [[f64; 2]; 8] = [
        [hw, -hh + c],
        [hw, hh - c],
        [hw - c, hh],
        [-hw + c, hh],
        [-hw, hh - c],
        [-hw, -hh + c],
        [-hw + c, -hh],
        [hw - c, -hh],
    ];
    let x_rear = nacelle.front_x - nacelle.length;
    for k in 0..8 {
        let (p0, p1) = (outline[k], outline[(k + 1) % 8]);
        let mid = [(p0[0] + p1[0]) / 2.0, (p0[1] + p1[1]) / 2.0];
        let n2 = normalize([0.0, p1[1] - p0[1], -(p1[0] - p0[0])]);
        let n2 = if n2[1] * mid[0] + n2[2] * mid[1] < 0.0 {
            scale(n2, -1.0)
        } else {
            n2
        };
        let o = f.p([x_rear, p0[0], hub_z + p0[1]]);
        let eu = f.d([nacelle.length, 0.0, 0.0]);
        let ev = f.d([0.0, p1[0] - p0[0], p1[1] - p0[1]]);
        mesh.flat_face(o, eu, ev, f.d(n2), alb, Tag::Other);
    }
    for (x, nx) in [(nacelle.front_x, 1.0), (x_rear, -1.0)] {
        let n = f.d([nx, 0.0, 0.0]);
        let centre = mesh.vert(f.p([x, 0.0, hub_z]), n, alb);
        let first = mesh.verts.len() as u32;
        for p in outline {
            mesh.vert(f.p([x, p[0], hub_z + p[1]]), n, alb);
        }
        for k in 0..8u32 {
            mesh.tri(centre, first + k, first + (k + 1) % 8, Tag::Other);
        }
    }

    // --- Spinner: surface of revolution around the rotor axis; nose = half ellipsoid.
    let hub_x = s.hub_overhang_m;
    let nseg = if high { SPINNER_SEGMENTS } else { 8 };
    let sr = s.spinner_radius_m;
    let sl = crate::scene::spinner_nose_length_m(sr);
    // Profile (axial offset from the blade-root plane, radius, axial normal, radial normal).
    let mut profile: [[f64; 4]; 12] = [[0.0; 4]; 12];
    profile[0] = [
        -SPINNER_BACK_M * sr / SPINNER_RADIUS_M,
        sr * 0.93,
        -0.3,
        1.0,
    ];
    profile[1] = [-0.5, sr, 0.0, 1.0];
    for k in 0..10 {
        let th = (k as f64 / 9.0) * std::f64::consts::FRAC_PI_2;
        let (ax, rad) = (sl * th.sin(), sr * th.cos());
        // Ellipse normal ∝ (x/a², r/b²).
        profile[2 + k] = [ax, rad, ax / (sl * sl), rad / (sr * sr)];
    }
    let mut prev: Option<u32> = None;
    for pr in profile {
        let ring = mesh.verts.len() as u32;
        for i in 0..nseg {
            let a = std::f64::consts::TAU * i as f64 / nseg as f64;
            let (ca, sa) = (a.cos(), a.sin());
            let local = [hub_x + pr[0], pr[1] * ca, hub_z + pr[1] * sa];
            let n = normalize([pr[2], pr[3] * ca, pr[3] * sa]);
            mesh.vert(f.p(local), f.d(n), alb);
        }
        if let Some(p) = prev {
            mesh.stitch_rings(p, ring, nseg, Tag::Other);
        }
        prev = Some(ring);
    }

    // --- Blades.
    let hub_local = [hub_x, 0.0, hub_z];
    for b in 0..3 {
        let th = deg(s.rotor_angle_deg + 120.0 * b as f64);
        // Clockwise seen from the front: 90° points to the viewer's right = turbine's left (+y).
        let e_r = [0.0, th.sin(), th.cos()];
        let e_t = [0.0, th.cos(), -th.sin()];
        build_blade(
            mesh,
            &f,
            hub_local,
            e_r,
            e_t,
            s.blade_length_m,
            s.blade_pitch_deg,
            high,
        );
    }
}

/// NACA 4-digit symmetric half thickness (fraction of chord) at chord position `s` (0 = LE).
fn naca_half_thickness(s: f64, t_ratio: f64) -> f64 {
    let s = s.clamp(0.0, 1.0);
    5.0 * t_ratio
        * (0.2969 * s.sqrt() - 0.1260 * s - 0.3516 * s * s + 0.2843 * s * s * s
            - 0.1036 * s.powi(4))
}

#[allow(clippy::too_many_arguments)]
fn build_blade(
    mesh: &mut Mesh,
    f: &Frame,
    hub: V3,
    e_r: V3,
    e_t: V3,
    len: f64,
    pitch_deg: f64,
    high: bool,
) {
    let k = len / BLADE_REF_LENGTH_M;
    let root_d = BLADE_ROOT_DIAMETER_M * k.powf(BLADE_ROOT_SCALING_EXP);
    let c_max = BLADE_MAX_CHORD_M * k.powf(BLADE_CHORD_SCALING_EXP);
    let c_tip = BLADE_TIP_CHORD_M * k.powf(BLADE_CHORD_SCALING_EXP);
    let r_cmax = BLADE_MAX_CHORD_FRAC * len;
    let npts = if high { BLADE_SECTION_POINTS } else { 6 };
    let axis = [1.0, 0.0, 0.0];

    // Stations: dense near the root where the shape changes, then every few metres.
    let mut radii: [f64; 40] = [0.0; 40];
    let mut nr = 0;
    let root_stations = [
        BLADE_ROOT_START_M,
        2.0,
        BLADE_ROOT_CYLINDER_END_M,
        3.6,
        4.6,
        5.6,
        r_cmax.max(6.2),
    ];
    for r in root_stations {
        radii[nr] = r * if r > BLADE_ROOT_CYLINDER_END_M {
            k.max(0.5)
        } else {
            1.0
        };
        nr += 1;
    }
    let step = if high {
        BLADE_STATION_STEP_M
    } else {
        len / 4.0
    };
    let mut r = radii[nr - 1];
    let r_end = len * 0.985;
    while r + step < r_end && nr < 37 {
        r += step;
        radii[nr] = r;
        nr += 1;
    }
    radii[nr] = r_end;
    nr += 1;

    let mut prev: Option<u32> = None;
    for &r in &radii[..nr] {
        // Shape blend: 0 = circle (root), 1 = airfoil.
        let w = crate::math::smoothstep(BLADE_ROOT_CYLINDER_END_M, r_cmax.max(6.2), r);
        let chord = if r <= r_cmax {
            root_d + (c_max - root_d) * w
        } else {
            let t = ((r - r_cmax) / (len - r_cmax)).clamp(0.0, 1.0);
            // Slightly convex taper, rounded off toward the tip.
            let lin = c_max + (c_tip - c_max) * t;
            let tip_round = if t > 0.9 {
                (1.0 - (t - 0.9) / 0.1 * 0.45).max(0.4)
            } else {
                1.0
            };
            lin * tip_round
        };
        let t_ratio = if r <= r_cmax {
            0.40
        } else {
            0.40 - 0.25 * ((r - r_cmax) / (len - r_cmax)).clamp(0.0, 1.0).sqrt()
        };
        let twist = if r <= r_cmax {
            BLADE_TWIST_DEG
        } else {
            BLADE_TWIST_DEG * (1.0 - ((r - r_cmax) / (len - r_cmax)).clamp(0.0, 1.0)).powf(1.5)
        };
        let beta = deg(pitch_deg + twist);
        // Chord direction (trailing edge -> leading edge): the direction of motion, turned upwind.
        let e_c = add(scale(e_t, beta.cos()), scale(axis, beta.sin()));
        let e_th = normalize(cross(e_r, e_c));
        let centre = add(hub, scale(e_r, r));
        let ring = mesh.verts.len() as u32;
        let mut pts2: [[f64; 2]; BLADE_SECTION_POINTS] = [[0.0; 2]; BLADE_SECTION_POINTS];
        for (i, p2) in pts2.iter_mut().enumerate().take(npts) {
            let phi = std::f64::consts::TAU * i as f64 / npts as f64;
            let circ = [root_d / 2.0 * phi.cos(), root_d / 2.0 * phi.sin()];
            let sc = (1.0 - phi.cos()) / 2.0;
            let ht = naca_half_thickness(sc, t_ratio) * chord;
            let foil = [
                (BLADE_PITCH_AXIS_FRAC - sc) * chord,
                if phi.sin() >= 0.0 { ht } else { -ht },
            ];
            *p2 = [
                circ[0] + (foil[0] - circ[0]) * w,
                circ[1] + (foil[1] - circ[1]) * w,
            ];
        }
        let cen2 = pts2[..npts].iter().fold([0.0, 0.0], |a, p| {
            [a[0] + p[0] / npts as f64, a[1] + p[1] / npts as f64]
        });
        for i in 0..npts {
            let (pm, pp) = (pts2[(i + npts - 1) % npts], pts2[(i + 1) % npts]);
            let tan = [pp[0] - pm[0], pp[1] - pm[1]];
            let mut n2 = [tan[1], -tan[0]];
            let out = [pts2[i][0] - cen2[0], pts2[i][1] - cen2[1]];
            if n2[0] * out[0] + n2[1] * out[1] < 0.0 {
                n2 = [-n2[0], -n2[1]];
            }
            let p = add(centre, add(scale(e_c, pts2[i][0]), scale(e_th, pts2[i][1])));
            let n = normalize(add(scale(e_c, n2[0]), scale(e_th, n2[1])));
            mesh.vert(f.p(p), f.d(n), TURBINE_ALBEDO);
        }
        if let Some(p) = prev {
            mesh.stitch_rings(p, ring, npts, Tag::Other);
        }
        prev = Some(ring);
    }
    // Tip cap: fan to a point just beyond the last station.
    if let Some(p) = prev {
        let tip = mesh.vert(f.p(add(hub, scale(e_r, len))), f.d(e_r), TURBINE_ALBEDO);
        for i in 0..npts as u32 {
            mesh.tri(p + i, p + (i + 1) % npts as u32, tip, Tag::Other);
        }
    }
}

/// Vertical tapered prism (lattice mast / pylon body stand-in), `n` sides.
fn build_pole(
    mesh: &mut Mesh,
    base: V3,
    height: f64,
    r_base: f64,
    r_top: f64,
    n: usize,
    albedo: [f32; 3],
) {
    let rings = ((height / 6.0).ceil() as usize).max(1);
    let slope = (r_top - r_base) / height;
    let mut prev: Option<u32> = None;
    for j in 0..=rings {
        let z = height * j as f64 / rings as f64;
        let r = r_base + slope * z;
        let ring = mesh.verts.len() as u32;
        for i in 0..n {
            let a = std::f64::consts::TAU * i as f64 / n as f64;
            let p = add(base, [r * a.cos(), r * a.sin(), z]);
            mesh.vert(p, normalize([a.cos(), a.sin(), -slope]), albedo);
        }
        if let Some(p) = prev {
            mesh.stitch_rings(p, ring, n, Tag::Other);
        }
        prev = Some(ring);
    }
}

/// Sagging cable between two points, split into short straight wires.
fn add_cable(mesh: &mut Mesh, a: V3, b: V3, sag_m: f64, width_m: f64) {
    const PIECES: usize = 24;
    let mut prev = a;
    for i in 1..=PIECES {
        let t = i as f64 / PIECES as f64;
        let mut p = lerp3(a, b, t);
        p[2] -= 4.0 * sag_m * t * (1.0 - t);
        mesh.wires.push(Wire {
            a: prev,
            b: p,
            width_m,
            albedo: CABLE_ALBEDO,
        });
        prev = p;
    }
}

/// Where a distractor stands: `x_m` along X (negative: behind the turbine, away from the usual
/// camera positions at +X) and `sideways_m` to either side; without a turbine, near where it
/// would be.
fn distractor_base(scene: &Scene, rng: &mut Rng, x_m: (f64, f64), sideways_m: (f64, f64)) -> V3 {
    if scene.turbine_present {
        let side = if rng.chance(0.5) { 1.0 } else { -1.0 };
        [
            rng.range(x_m.0, x_m.1),
            side * rng.range(sideways_m.0, sideways_m.1),
            0.0,
        ]
    } else {
        [rng.range(-20.0, 10.0), rng.range(-15.0, 15.0), 0.0]
    }
}

/// A guyed meteorological mast near the turbine (or where the turbine would be).
pub(crate) fn build_mast(mesh: &mut Mesh, scene: &Scene, rng: &mut Rng) {
    let base = distractor_base(scene, rng, (-120.0, -40.0), (50.0, 110.0));
    let h = rng.range(55.0, 85.0);
    // Lattice mast: thin triangular section, lattice drawn as wires on top of a faint body.
    const MAST_HALF_WIDTH_M: f64 = 0.35;
    build_pole(
        mesh,
        base,
        h,
        MAST_HALF_WIDTH_M,
        MAST_HALF_WIDTH_M,
        3,
        STEEL_ALBEDO,
    );
    // Guy wires at three heights to three anchors.
    for level in [0.35, 0.65, 0.95] {
        for k in 0..3 {
            let a = std::f64::consts::TAU * k as f64 / 3.0 + 0.4;
            let anchor = add(base, [h * 0.45 * a.cos(), h * 0.45 * a.sin(), 0.0]);
            mesh.wires.push(Wire {
                a: add(base, [0.0, 0.0, h * level]),
                b: anchor,
                width_m: 0.02,
                albedo: CABLE_ALBEDO,
            });
        }
    }
    // Boom arms with instruments near the top.
    for z in [h - 2.0, h * 0.6] {
        mesh.wires.push(Wire {
            a: add(base, [0.0, 0.0, z]),
            b: add(base, [0.0, 3.0, z]),
            width_m: 0.08,
            albedo: STEEL_ALBEDO,
        });
    }
}

/// An industrial chimney near the turbine (or where the turbine would be): a smooth tapered
/// concrete column 60–130 m tall, 4–10 m across at the base and 2.5–4.5 m at the top — a
/// turbine tower's proportions without its nacelle and rotor.
pub(crate) fn build_chimney(mesh: &mut Mesh, scene: &Scene, rng: &mut Rng) {
    let base = distractor_base(scene, rng, (-150.0, -30.0), (30.0, 120.0));
    let h = rng.range(60.0, 130.0);
    let r_top = rng.range(1.25, 2.25);
    let r_base = r_top * rng.range(1.6, 2.2);
    const CHIMNEY_SIDES: usize = 20;
    build_pole(mesh, base, h, r_base, r_top, CHIMNEY_SIDES, CONCRETE_ALBEDO);
}

/// A lattice pylon (wireframe: legs, braces, cross arms). Returns the conductor attachment points.
/// `along` is the direction of the line (conductors run along it; cross arms are perpendicular).
fn build_pylon(mesh: &mut Mesh, base: V3, h: f64, along: V3) -> [V3; 6] {
    let across = [-along[1], along[0], 0.0];
    let (wb, wt) = (4.0, 1.2);
    let leg = |z: f64, sx: f64, sy: f64| -> V3 {
        let w = wb + (wt - wb) * (z / h);
        add(
            base,
            add(
                add(scale(along, sx * w), scale(across, sy * w)),
                [0.0, 0.0, z],
            ),
        )
    };
    let corners = [(1.0, 1.0), (1.0, -1.0), (-1.0, -1.0), (-1.0, 1.0)];
    let levels = 8;
    for l in 0..levels {
        let (z0, z1) = (
            h * l as f64 / levels as f64,
            h * (l + 1) as f64 / levels as f64,
        );
        for k in 0..4 {
            let (a, b) = (corners[k], corners[(k + 1) % 4]);
            let w = 0.15;
            mesh.wires.push(Wire {
                a: leg(z0, a.0, a.1),
                b: leg(z1, a.0, a.1),
                width_m: 0.25,
                albedo: STEEL_ALBEDO,
            });
            mesh.wires.push(Wire {
                a: leg(z0, a.0, a.1),
                b: leg(z1, b.0, b.1),
                width_m: w,
                albedo: STEEL_ALBEDO,
            });
            mesh.wires.push(Wire {
                a: leg(z1, a.0, a.1),
                b: leg(z1, b.0, b.1),
                width_m: w,
                albedo: STEEL_ALBEDO,
            });
        }
    }
    let mut pts = [[0.0; 3]; 6];
    for (i, (z, span)) in [(h * 0.72, 7.0), (h * 0.86, 5.5)].iter().enumerate() {
        let a = add(base, add(scale(across, -span), [0.0, 0.0, *z]));
        let b = add(base, add(scale(across, *span), [0.0, 0.0, *z]));
        mesh.wires.push(Wire {
            a,
            b,
            width_m: 0.6,
            albedo: STEEL_ALBEDO,
        });
        pts[i * 3] = add(a, [0.0, 0.0, -2.0]);
        pts[i * 3 + 1] = add(b, [0.0, 0.0, -2.0]);
        pts[i * 3 + 2] = add(base, [0.0, 0.0, h]);
    }
    pts
}

/// A line of pylons behind the turbine site, with sagging conductors.
pub(crate) fn build_power_lines(mesh: &mut Mesh, rng: &mut Rng) {
    let x_line = rng.range(-260.0, -90.0);
    let angle = deg(rng.range(-25.0, 25.0));
    // Pylons run roughly along the world Y axis (across the typical line of sight).
    let along = [angle.sin(), angle.cos(), 0.0];
    let spacing = rng.range(220.0, 320.0);
    let h = rng.range(30.0, 42.0);
    let offset = rng.range(-spacing / 2.0, spacing / 2.0);
    let mut prev: Option<[V3; 6]> = None;
    for i in -6..=6 {
        let base = add(
            [x_line, 0.0, 0.0],
            scale(along, offset + i as f64 * spacing),
        );
        let pts = build_pylon(mesh, base, h, along);
        if let Some(p) = prev {
            for k in 0..6 {
                add_cable(mesh, p[k], pts[k], spacing * 0.03, 0.03);
            }
        }
        prev = Some(pts);
    }
}

/// Two rings of hills on the horizon (a nearer one 2.5–4 km away and a higher, farther one
/// 5–7 km away), drawn far ridge first behind everything else. Heights are sums of random
/// sinusoids; normals come from the actual surface so slopes shade with the sun.
pub(crate) fn build_hills(mesh: &mut Mesh, seed: u64) {
    let mut rng = Rng::new(seed, 0x4111);
    // (front radius m, depth m, mean height m, albedo)
    let ridges = [
        (
            rng.range(5000.0, 6500.0),
            1500.0,
            rng.range(180.0, 320.0),
            [0.27f32, 0.34, 0.26],
        ),
        (
            rng.range(2500.0, 3500.0),
            1000.0,
            rng.range(70.0, 160.0),
            [0.28f32, 0.38, 0.22],
        ),
    ];
    for (front, depth, mean_h, albedo) in ridges {
        build_ridge(mesh, &mut rng, front, depth, mean_h, albedo);
    }
}

fn build_ridge(
    mesh: &mut Mesh,
    rng: &mut Rng,
    front: f64,
    depth: f64,
    mean_h: f64,
    albedo: [f32; 3],
) {
    const SEGMENTS: usize = 360;
    const ROWS: usize = 5;
    let mut harm = [[0.0f64; 3]; 8];
    for (i, h) in harm.iter_mut().enumerate() {
        let k = ((i + 1) as f64 * 2.3 + rng.range(0.0, 2.0)).round();
        *h = [
            k,
            rng.range(0.0, std::f64::consts::TAU),
            1.0 / (1.0 + i as f64 * 0.7),
        ];
    }
    let patch_seed = rng.next_u64();
    let height = |a: f64, frac: f64| -> f64 {
        let mut prof = 0.0;
        for h in &harm {
            prof += h[2] * (h[0] * a + h[1] + 2.0 * frac).sin();
        }
        // Rises from the plain at the front edge to the crest at the back.
        let rise = (frac * std::f64::consts::FRAC_PI_2).sin();
        (mean_h * (1.0 + 0.45 * prof) * rise).max(0.0) - 3.0
    };
    // Positions first (the height function is costly), then normals from neighbours.
    let mut grid = [[0.0f64; 3]; SEGMENTS * ROWS];
    for i in 0..SEGMENTS {
        let a = std::f64::consts::TAU * i as f64 / SEGMENTS as f64;
        let (ca, sa) = (a.cos(), a.sin());
        for r in 0..ROWS {
            let frac = r as f64 / (ROWS - 1) as f64;
            let rad = front + depth * frac;
            grid[i * ROWS + r] = [rad * ca, rad * sa, height(a, frac)];
        }
    }
    let pos = |i: usize, r: usize| grid[i * ROWS + r];
    let first = mesh.verts.len() as u32;
    for i in 0..SEGMENTS {
        for r in 0..ROWS {
            let p = pos(i, r);
            // Normal from the surface: cross of the azimuthal and radial tangents.
            let ta = sub(
                pos((i + 1) % SEGMENTS, r),
                pos((i + SEGMENTS - 1) % SEGMENTS, r),
            );
            let tr = sub(pos(i, (r + 1).min(ROWS - 1)), pos(i, r.saturating_sub(1)));
            let mut n = normalize(cross(tr, ta));
            if n[2] < 0.0 {
                n = scale(n, -1.0);
            }
            // Patches of forest / fields on the slopes.
            let h = crate::math::hash64(patch_seed ^ ((i / 6) as u64 * 31 + r as u64));
            let k = 0.75 + 0.5 * ((h >> 40) as f32 / (1u64 << 24) as f32);
            let alb = [albedo[0] * k, albedo[1] * k, albedo[2] * (0.9 + 0.2 * k)];
            mesh.vert(p, n, alb);
        }
    }
    // Back rows first: without depth testing the nearer slope must be drawn last.
    for r in (0..ROWS - 1).rev() {
        for i in 0..SEGMENTS as u32 {
            let j = (i + 1) % SEGMENTS as u32;
            let at = |seg: u32, row: usize| first + seg * ROWS as u32 + row as u32;
            mesh.quad(at(i, r), at(j, r), at(j, r + 1), at(i, r + 1), Tag::Other);
        }
    }
}
