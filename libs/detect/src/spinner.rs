//! Spinner (nose cone) circles from edge points with gradient directions: a gradient Hough vote
//! for the centre, then the radius with the best rim coverage, then an algebraic circle fit.
//! Plain data, no OpenCV, so it is unit-testable on constructed rims.

use crate::geometry::P2;

/// One edge pixel: position and unit gradient direction (working px).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct EdgePoint {
    pub p: P2,
    pub u: P2,
}

/// Settings of [`find_circles`].
#[derive(Debug, Clone, Copy)]
pub(crate) struct CircleSearch {
    /// Region `[x0, y0, x1, y1]` searched for centres (the points may lie outside it).
    pub roi: [f64; 4],
    pub min_r: f64,
    pub max_r: f64,
    /// Accumulator cell and radius step, px.
    pub cell: f64,
    /// An edge point belongs to a rim when its gradient is within this of the radial direction (cos).
    pub radial_cos: f64,
    /// Smallest accepted fraction of the rim covered by edge points.
    pub min_coverage: f64,
    /// Largest accepted density of edge points (per px²) inside [`INNER_FRAC`] of the radius:
    /// a spinner is a smooth body, a "circle" in clutter is full of edges.
    pub max_interior_density: f64,
    /// Centre peaks examined.
    pub max_peaks: usize,
    /// Every this-many-th point votes for centres (at least 1); all of them count on the rims.
    pub vote_every: usize,
    /// The image's size `[w, h]` (working px) when a rim's coverage is to count only its part
    /// inside the image, no less than [`MIN_VISIBLE_RIM`] of it: close in the spinner overflows
    /// the frame, and its rim outside cannot have edges. Only where its size is known (the
    /// tracker's distance): a small arc in a corner must not pass for a whole spinner.
    pub visible_in: Option<[f64; 2]>,
}

/// The least share of a rim counted as its visible part (see [`CircleSearch::visible_in`]).
pub(crate) const MIN_VISIBLE_RIM: f64 = 0.5;
/// Points along a rim sampled for its visible share.
const VISIBLE_RIM_SAMPLES: usize = 64;

/// The share of the circle `(c, r)` inside `[0, w) × [0, h)`, at least [`MIN_VISIBLE_RIM`].
fn visible_rim(c: P2, r: f64, [w, h]: [f64; 2]) -> f64 {
    // Most circles lie wholly inside: no sampling.
    if c[0] - r >= 0.0 && c[0] + r < w && c[1] - r >= 0.0 && c[1] + r < h {
        return 1.0;
    }
    let inside = rim_directions()
        .iter()
        .filter(|u| {
            let (x, y) = (c[0] + r * u[0], c[1] + r * u[1]);
            (0.0..w).contains(&x) && (0.0..h).contains(&y)
        })
        .count();
    (inside as f64 / VISIBLE_RIM_SAMPLES as f64).max(MIN_VISIBLE_RIM)
}

/// The unit directions of the [`VISIBLE_RIM_SAMPLES`] rim samples, computed once.
fn rim_directions() -> &'static [P2; VISIBLE_RIM_SAMPLES] {
    static DIRECTIONS: std::sync::OnceLock<[P2; VISIBLE_RIM_SAMPLES]> = std::sync::OnceLock::new();
    DIRECTIONS.get_or_init(|| {
        std::array::from_fn(|k| {
            let a = k as f64 * std::f64::consts::TAU / VISIBLE_RIM_SAMPLES as f64;
            [a.cos(), a.sin()]
        })
    })
}

/// The interior whose edge density is limited, fraction of the radius (the nose highlight and
/// the blade roots lie outside it).
pub(crate) const INNER_FRAC: f64 = 0.7;

/// One accumulator cell in the 32.32 fixed point of the centre vote.
const FIXED_ONE: f64 = (1u64 << 32) as f64;

/// Circles `[x, y, r, coverage]` among `points`, best coverage first.
pub(crate) fn find_circles(points: &[EdgePoint], cs: &CircleSearch) -> Vec<[f64; 4]> {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: the CPU has AVX2 (checked just above).
        return unsafe { find_circles_avx2(points, cs) };
    }
    find_circles_here(points, cs)
}

/// [`find_circles`] compiled for AVX2: the same arithmetic (IEEE operations are the same in
/// any vector width, and nothing is fused), four lanes where the compiler vectorises.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn find_circles_avx2(points: &[EdgePoint], cs: &CircleSearch) -> Vec<[f64; 4]> {
    find_circles_here(points, cs)
}

#[inline(always)]
fn find_circles_here(points: &[EdgePoint], cs: &CircleSearch) -> Vec<[f64; 4]> {
    let (acc, gw, gh) = vote_centres(points, cs);
    peaks_and_rims(points, cs, &acc, gw, gh)
}

/// The accumulator grid of the centre vote (`gw`×`gh` cells of `cs.cell` over `cs.roi`): each
/// point votes along its gradient ray, both ways, at radii `min_r + k·cell` up to `max_r`.
#[inline(always)]
fn vote_centres(points: &[EdgePoint], cs: &CircleSearch) -> (Vec<u32>, usize, usize) {
    let [x0, y0, x1, y1] = cs.roi;
    let gw = ((x1 - x0) / cs.cell).ceil().max(1.0) as usize;
    let gh = ((y1 - y0) / cs.cell).ceil().max(1.0) as usize;
    let mut acc = vec![0u32; gw * gh];
    let (bw, bh) = (gw as f64 * cs.cell, gh as f64 * cs.cell);
    for e in points.iter().step_by(cs.vote_every.max(1)) {
        for sign in [-1.0, 1.0] {
            let v = [sign * e.u[0], sign * e.u[1]];
            // Clip the ray p + r v to the centre box (slab method) and to [min_r, max_r].
            let (mut lo, mut hi) = (cs.min_r, cs.max_r);
            for (q, d, size) in [(e.p[0] - x0, v[0], bw), (e.p[1] - y0, v[1], bh)] {
                if d.abs() < 1e-12 {
                    if q < 0.0 || q >= size {
                        hi = -1.0;
                    }
                    continue;
                }
                let (t0, t1) = ((0.0 - q) / d, (size - q) / d);
                lo = lo.max(t0.min(t1));
                hi = hi.min(t0.max(t1));
            }
            if hi < lo {
                continue;
            }
            // Radii on the grid min_r + k·cell inside [lo, hi].
            let k0 = ((lo - cs.min_r) / cs.cell).ceil().max(0.0) as usize;
            let k1 = ((hi - cs.min_r) / cs.cell).floor() as usize;
            // Walk the ray in cell units, one cell of radius per step, in 32.32 fixed point:
            // this loop is most of the spinner step's time, and integer steps make the cell
            // index a shift and the bounds test one unsigned compare (a negative index wraps
            // to a huge one). The rounding differs from f64 steps by < 1e-8 cell after
            // hundreds of steps.
            let r0 = cs.min_r + k0 as f64 * cs.cell;
            let (cx, cy) = (
                (e.p[0] + r0 * v[0] - x0) / cs.cell,
                (e.p[1] + r0 * v[1] - y0) / cs.cell,
            );
            let (mut fx, mut fy) = (
                (cx * FIXED_ONE).floor() as i64,
                (cy * FIXED_ONE).floor() as i64,
            );
            let (dx, dy) = (
                (v[0] * FIXED_ONE).round() as i64,
                (v[1] * FIXED_ONE).round() as i64,
            );
            for _ in k0..=k1 {
                let (gx, gy) = ((fx >> 32) as usize, (fy >> 32) as usize);
                if gx < gw && gy < gh {
                    acc[gy * gw + gx] += 1;
                }
                fx += dx;
                fy += dy;
            }
        }
    }
    (acc, gw, gh)
}

/// The strongest centres of the vote `acc` and the circles around them (see [`find_circles`]).
#[inline(always)]
fn peaks_and_rims(
    points: &[EdgePoint],
    cs: &CircleSearch,
    acc: &[u32],
    gw: usize,
    gh: usize,
) -> Vec<[f64; 4]> {
    let [x0, y0, ..] = cs.roi;
    // 3x3 sums (a row pass, then a column pass), then the strongest peaks at least min_r
    // apart (repeated arg-max, no sort).
    let mut rows = vec![0u32; gw * gh];
    for (src, dst) in acc.chunks_exact(gw).zip(rows.chunks_exact_mut(gw)) {
        for gx in 0..gw {
            dst[gx] = src[gx.saturating_sub(1)..(gx + 2).min(gw)].iter().sum();
        }
    }
    let mut sums = vec![0u32; gw * gh];
    for gy in 0..gh {
        let (lo, hi) = (gy.saturating_sub(1), (gy + 2).min(gh));
        let dst = &mut sums[gy * gw..(gy + 1) * gw];
        for yy in lo..hi {
            for (d, s) in dst.iter_mut().zip(&rows[yy * gw..(yy + 1) * gw]) {
                *d += s;
            }
        }
    }
    let mut centres: Vec<P2> = Vec::new();
    while centres.len() < cs.max_peaks {
        // The last of equal maxima (as `Iterator::max_by_key` picks them): the maximum, then
        // its last position, two passes that vectorise, several times faster here than one
        // pass tracking the index.
        let v = sums.iter().copied().max().unwrap_or(0);
        let i = sums.iter().rposition(|&s| s == v).unwrap_or(0);
        if v == 0 {
            break;
        }
        let c = [
            x0 + ((i % gw) as f64 + 0.5) * cs.cell,
            y0 + ((i / gw) as f64 + 0.5) * cs.cell,
        ];
        centres.push(c);
        // Suppress the neighbourhood of this peak.
        let rad = (cs.min_r / cs.cell).ceil() as usize;
        let (px, py) = (i % gw, i / gw);
        for yy in py.saturating_sub(rad)..(py + rad + 1).min(gh) {
            for xx in px.saturating_sub(rad)..(px + rad + 1).min(gw) {
                sums[yy * gw + xx] = 0;
            }
        }
    }
    // Points in row order (as the detector collects them) let each rim read only the rows it
    // can reach.
    let sorted = points.is_sorted_by(|a, b| a.p[1] <= b.p[1]);
    let mut out: Vec<[f64; 4]> = centres
        .into_iter()
        .filter_map(|c| rim(points, sorted, c, cs))
        .collect();
    out.sort_by(|a, b| b[3].total_cmp(&a[3]));
    out
}

/// The best-covered radius around `c`, refined by a circle fit; `None` below `min_coverage`.
/// `sorted`: `points` are in row order.
#[inline(always)]
fn rim(points: &[EdgePoint], sorted: bool, c: P2, cs: &CircleSearch) -> Option<[f64; 4]> {
    let nb = cs.max_r.ceil() as usize + 2;
    let mut hist = vec![0u32; nb];
    // The ring's squared bounds.
    let (lo2, hi2) = ((cs.min_r - 1.0).max(0.0).powi(2), (cs.max_r + 1.0).powi(2));
    // Whether `e` lies in the ring with its gradient radial, and its distance from `c`:
    // computed for every point and kept or not without a branch (whether a point is in the
    // ring is a coin toss for the branch predictor, and mispredictions were most of the time).
    let radial = |e: &EdgePoint, c: P2| -> (bool, f64) {
        let (vx, vy) = (e.p[0] - c[0], e.p[1] - c[1]);
        let d2 = vx * vx + vy * vy;
        let d = d2.sqrt();
        let ok = (d2 >= lo2)
            & (d2 <= hi2)
            & (d2 != 0.0)
            & ((vx * e.u[0] + vy * e.u[1]).abs() / d >= cs.radial_cos);
        (ok, d)
    };
    // The radial points with their distances, kept for the rim fit below (one pass over all
    // points instead of two).
    // Only rows within the outer radius can hold radial points (a px of margin for rounding).
    let reach = cs.max_r + 2.0;
    let band = rows_between(points, sorted, c[1] - reach, c[1] + reach);
    let mut ring: Vec<(P2, f64)> = vec![([0.0; 2], 0.0); band.len()];
    let mut n = 0;
    let mut scalar_from = 0;
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: the CPU has AVX2 (checked just above).
        (n, scalar_from) = unsafe { radial_ring_avx2(band, c, lo2, hi2, cs.radial_cos, &mut ring) };
    }
    for e in &band[scalar_from..] {
        let (ok, d) = radial(e, c);
        ring[n] = (e.p, d);
        n += ok as usize;
    }
    ring.truncate(n);
    for &(_, d) in &ring {
        hist[(d.round() as usize).min(nb - 1)] += 1;
    }
    let (mut best_r, mut best_cov) = (0.0, 0.0);
    for r in (cs.min_r.ceil() as usize)..=(cs.max_r.floor() as usize).min(nb - 2) {
        let n = hist[r - 1] + hist[r] + hist[r + 1];
        let seen = cs
            .visible_in
            .map_or(1.0, |size| visible_rim(c, r as f64, size));
        let cov = n as f64 / (2.0 * std::f64::consts::PI * r as f64 * seen);
        if cov > best_cov {
            (best_r, best_cov) = (r as f64, cov);
        }
    }
    if best_cov < cs.min_coverage {
        return None;
    }
    // Kåsa fit on the rim points: x² + y² + D x + E y + F = 0, least squares.
    let tol = (0.1 * best_r).max(1.5);
    let rim_pts: Vec<P2> = ring
        .iter()
        .filter(|(_, d)| (d - best_r).abs() <= tol)
        .map(|(p, _)| *p)
        .collect();
    let fit = fit_circle(&rim_pts).filter(|f| {
        crate::geometry::dist([f[0], f[1]], c) <= tol + cs.cell && (f[2] - best_r).abs() <= tol
    });
    let [x, y, r] = fit.unwrap_or([c[0], c[1], best_r]);
    let inner2 = (INNER_FRAC * r).powi(2);
    let inner = INNER_FRAC * r + 1.0;
    let inside = rows_between(points, sorted, y - inner, y + inner)
        .iter()
        .filter(|e| (e.p[0] - x).powi(2) + (e.p[1] - y).powi(2) < inner2)
        .count();
    if inside as f64 > cs.max_interior_density * std::f64::consts::PI * inner2 {
        return None;
    }
    Some([x, y, r, best_cov.min(1.0)])
}

/// The radial test of [`rim`] four points at a time: the points of `band` (whole groups of
/// four) that lie in the ring `lo2 ≤ d² ≤ hi2` around `c` with their gradient within
/// `radial_cos` of the radial direction, written to the front of `ring` with their distances.
/// Returns how many were kept and how many points were read. The same IEEE operations in the
/// same order as the scalar test (nothing fused), so the same points and distances; the
/// square root and division of every point were most of the rim search's time.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn radial_ring_avx2(
    band: &[EdgePoint],
    c: P2,
    lo2: f64,
    hi2: f64,
    radial_cos: f64,
    ring: &mut [(P2, f64)],
) -> (usize, usize) {
    use std::arch::x86_64::*;
    debug_assert!(ring.len() >= band.len());
    let groups = band.len() / 4;
    let (cx, cy) = (_mm256_set1_pd(c[0]), _mm256_set1_pd(c[1]));
    let (lo, hi, cos, zero) = (
        _mm256_set1_pd(lo2),
        _mm256_set1_pd(hi2),
        _mm256_set1_pd(radial_cos),
        _mm256_setzero_pd(),
    );
    let sign = _mm256_set1_pd(-0.0);
    let mut n = 0;
    let mut d_lanes = [0.0f64; 4];
    for (g, quad) in band.chunks_exact(4).enumerate() {
        // `EdgePoint` is four f64 (p.x, p.y, u.x, u.y): load four points and transpose.
        let base = quad.as_ptr() as *const f64;
        let (r0, r1, r2, r3) = (
            _mm256_loadu_pd(base),
            _mm256_loadu_pd(base.add(4)),
            _mm256_loadu_pd(base.add(8)),
            _mm256_loadu_pd(base.add(12)),
        );
        let (t0, t1) = (_mm256_unpacklo_pd(r0, r1), _mm256_unpackhi_pd(r0, r1));
        let (t2, t3) = (_mm256_unpacklo_pd(r2, r3), _mm256_unpackhi_pd(r2, r3));
        let (px, ux) = (
            _mm256_permute2f128_pd(t0, t2, 0x20),
            _mm256_permute2f128_pd(t0, t2, 0x31),
        );
        let (py, uy) = (
            _mm256_permute2f128_pd(t1, t3, 0x20),
            _mm256_permute2f128_pd(t1, t3, 0x31),
        );
        let (vx, vy) = (_mm256_sub_pd(px, cx), _mm256_sub_pd(py, cy));
        let d2 = _mm256_add_pd(_mm256_mul_pd(vx, vx), _mm256_mul_pd(vy, vy));
        let d = _mm256_sqrt_pd(d2);
        let dot = _mm256_add_pd(_mm256_mul_pd(vx, ux), _mm256_mul_pd(vy, uy));
        let q = _mm256_div_pd(_mm256_andnot_pd(sign, dot), d);
        let ok = _mm256_and_pd(
            _mm256_and_pd(
                _mm256_cmp_pd::<_CMP_GE_OQ>(d2, lo),
                _mm256_cmp_pd::<_CMP_LE_OQ>(d2, hi),
            ),
            _mm256_and_pd(
                _mm256_cmp_pd::<_CMP_NEQ_UQ>(d2, zero),
                _mm256_cmp_pd::<_CMP_GE_OQ>(q, cos),
            ),
        );
        let bits = _mm256_movemask_pd(ok) as usize;
        _mm256_storeu_pd(d_lanes.as_mut_ptr(), d);
        for (lane, (e, dl)) in quad.iter().zip(d_lanes).enumerate() {
            // SAFETY of the index: n ≤ 4·g + lane < band.len() ≤ ring.len().
            *ring.get_unchecked_mut(n) = (e.p, dl);
            n += (bits >> lane) & 1;
        }
        debug_assert!(n <= 4 * (g + 1));
    }
    (n, 4 * groups)
}

/// The points with a row in `[y0, y1]`, a sub-slice in the same order, when `sorted` by row;
/// else all of them.
#[inline(always)]
fn rows_between(points: &[EdgePoint], sorted: bool, y0: f64, y1: f64) -> &[EdgePoint] {
    if !sorted {
        return points;
    }
    let a = points.partition_point(|e| e.p[1] < y0);
    let b = points.partition_point(|e| e.p[1] <= y1).max(a);
    &points[a..b]
}

/// Algebraic (Kåsa) least-squares circle through `pts`: `[x, y, r]`; `None` if degenerate.
pub(crate) fn fit_circle(pts: &[P2]) -> Option<[f64; 3]> {
    if pts.len() < 3 {
        return None;
    }
    let n = pts.len() as f64;
    let (mx, my) = (
        pts.iter().map(|p| p[0]).sum::<f64>() / n,
        pts.iter().map(|p| p[1]).sum::<f64>() / n,
    );
    let (mut suu, mut suv, mut svv, mut suuu, mut svvv, mut suvv, mut svuu) =
        (0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0);
    for p in pts {
        let (u, v) = (p[0] - mx, p[1] - my);
        suu += u * u;
        suv += u * v;
        svv += v * v;
        suuu += u * u * u;
        svvv += v * v * v;
        suvv += u * v * v;
        svuu += v * u * u;
    }
    let det = suu * svv - suv * suv;
    if det.abs() < 1e-9 {
        return None;
    }
    let (b1, b2) = (0.5 * (suuu + suvv), 0.5 * (svvv + svuu));
    let uc = (b1 * svv - b2 * suv) / det;
    let vc = (suu * b2 - suv * b1) / det;
    let r = (uc * uc + vc * vc + (suu + svv) / n).sqrt();
    Some([uc + mx, vc + my, r])
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The centre vote stepped in f64 (how it was written before the fixed-point loop).
    fn vote_reference(points: &[EdgePoint], cs: &CircleSearch) -> Vec<u32> {
        let [x0, y0, x1, y1] = cs.roi;
        let gw = ((x1 - x0) / cs.cell).ceil().max(1.0) as usize;
        let gh = ((y1 - y0) / cs.cell).ceil().max(1.0) as usize;
        let mut acc = vec![0u32; gw * gh];
        for e in points {
            for sign in [-1.0, 1.0] {
                let v = [sign * e.u[0], sign * e.u[1]];
                let mut r = cs.min_r;
                while r <= cs.max_r {
                    let (cx, cy) = (
                        (e.p[0] + r * v[0] - x0) / cs.cell,
                        (e.p[1] + r * v[1] - y0) / cs.cell,
                    );
                    if cx >= 0.0 && cy >= 0.0 && (cx as usize) < gw && (cy as usize) < gh {
                        acc[cy as usize * gw + cx as usize] += 1;
                    }
                    r += cs.cell;
                }
            }
        }
        acc
    }

    #[test]
    fn rims_read_only_the_rows_they_reach_and_find_the_same_circles_in_any_order() {
        let mut pts = rim_points([60.0, 60.0], 20.0, &[(0.0, 360.0)]);
        pts.extend(rim_points([30.0, 100.0], 8.0, &[(0.0, 360.0)]));
        let unsorted = pts.clone();
        pts.sort_by(|a, b| a.p[1].total_cmp(&b.p[1]));
        let window = rows_between(&pts, true, 38.0, 82.0);
        assert!(window.iter().all(|e| (38.0..=82.0).contains(&e.p[1])));
        assert_eq!(
            window.len(),
            pts.iter()
                .filter(|e| (38.0..=82.0).contains(&e.p[1]))
                .count()
        );
        assert_eq!(
            rows_between(&unsorted, false, 38.0, 82.0).len(),
            unsorted.len()
        );
        let (a, b) = (
            find_circles(&pts, &search()),
            find_circles(&unsorted, &search()),
        );
        assert!(!a.is_empty());
        assert_eq!(a.len(), b.len());
        for (x, y) in a.iter().zip(&b) {
            assert!((0..4).all(|i| (x[i] - y[i]).abs() < 1e-9), "{x:?} vs {y:?}");
        }
    }

    #[test]
    fn the_fixed_point_vote_lands_in_the_cells_of_floating_point_steps() {
        // Points all over and around the box, gradients in every direction (a fixed LCG, so
        // the test is the same every run): rays that start outside, leave, or run along it.
        let mut state = 12345u64;
        let mut next = || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        let points: Vec<EdgePoint> = (0..3000)
            .map(|_| {
                let t = next() * std::f64::consts::TAU;
                EdgePoint {
                    p: [
                        (next() * 200.0 - 40.0).round(),
                        (next() * 160.0 - 30.0).round(),
                    ],
                    u: [t.cos(), t.sin()],
                }
            })
            .collect();
        let cs = CircleSearch {
            roi: [10.0, 5.0, 130.0, 95.0],
            ..search()
        };
        let (acc, gw, gh) = vote_centres(&points, &cs);
        let reference = vote_reference(&points, &cs);
        assert_eq!((gw, gh), (60, 45));
        let differing = acc.iter().zip(&reference).filter(|(a, b)| a != b).count();
        assert!(
            acc.iter().sum::<u32>() > 10_000,
            "the rays must reach the box"
        );
        assert_eq!(differing, 0, "{differing} cells differ from the f64 vote");
    }

    /// The four-lane radial test keeps exactly the points, in the same order and with the same
    /// distances, that the scalar test of `rim` keeps: random points around a centre (some on
    /// it, where the distance is 0), gradients in every direction, a count not divisible by 4.
    #[cfg(target_arch = "x86_64")]
    #[test]
    fn the_four_lane_radial_test_keeps_what_the_scalar_one_keeps() {
        if !std::arch::is_x86_feature_detected!("avx2") {
            eprintln!("skipped: no AVX2 on this CPU");
            return;
        }
        let mut state = 777u64;
        let mut next = || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        let c = [50.0, 40.0];
        let band: Vec<EdgePoint> = (0..4003)
            .map(|i| {
                let t = next() * std::f64::consts::TAU;
                let p = if i % 97 == 0 {
                    c
                } else {
                    [(next() * 100.0).round(), (next() * 80.0).round()]
                };
                EdgePoint {
                    p,
                    u: [t.cos(), t.sin()],
                }
            })
            .collect();
        let (lo2, hi2, cos) = (3.0f64.powi(2), 31.0f64.powi(2), 0.9);
        // The lanes read whole groups of four; the caller tests the rest as before.
        let scalar: Vec<(P2, f64)> = band[..4000]
            .iter()
            .filter_map(|e| {
                let (vx, vy) = (e.p[0] - c[0], e.p[1] - c[1]);
                let d2 = vx * vx + vy * vy;
                let d = d2.sqrt();
                let ok = (d2 >= lo2)
                    & (d2 <= hi2)
                    & (d2 != 0.0)
                    & ((vx * e.u[0] + vy * e.u[1]).abs() / d >= cos);
                ok.then_some((e.p, d))
            })
            .collect();
        let mut ring = vec![([0.0; 2], 0.0); band.len()];
        // SAFETY: AVX2 checked above.
        let (n, read) = unsafe { radial_ring_avx2(&band, c, lo2, hi2, cos, &mut ring) };
        assert_eq!(read, 4000);
        assert!(n > 300, "too few kept ({n}) for a meaningful test");
        assert_eq!(&ring[..n], &scalar[..]);
    }

    /// Rim points of a circle, with outward gradients, over the given arcs (degrees).
    fn rim_points(c: P2, r: f64, arcs: &[(f64, f64)]) -> Vec<EdgePoint> {
        let mut v = Vec::new();
        for &(a0, a1) in arcs {
            let mut a = a0;
            while a < a1 {
                let t = a.to_radians();
                let u = [t.cos(), t.sin()];
                v.push(EdgePoint {
                    p: [(c[0] + r * u[0]).round(), (c[1] + r * u[1]).round()],
                    u,
                });
                a += 360.0 / (2.0 * std::f64::consts::PI * r);
            }
        }
        v
    }

    fn search() -> CircleSearch {
        CircleSearch {
            roi: [0.0, 0.0, 120.0, 120.0],
            min_r: 4.0,
            max_r: 40.0,
            cell: 2.0,
            radial_cos: 0.9,
            min_coverage: 0.4,
            max_interior_density: 0.05,
            max_peaks: 3,
            vote_every: 1,
            visible_in: None,
        }
    }

    #[test]
    fn circle_broken_by_blades_is_found_and_fitted() {
        let c = [61.3, 57.8];
        // Three blade roots hide three 50° stretches of the rim.
        let mut pts = rim_points(c, 20.0, &[(0.0, 70.0), (120.0, 190.0), (240.0, 310.0)]);
        // A straight blade edge nearby must not make a circle.
        pts.extend((0..40).map(|k| EdgePoint {
            p: [90.0 + k as f64, 20.0],
            u: [0.0, 1.0],
        }));
        let found = find_circles(&pts, &search());
        assert!(!found.is_empty());
        let f = found[0];
        assert!(crate::geometry::dist([f[0], f[1]], c) < 1.0, "{f:?}");
        assert!((f[2] - 20.0).abs() < 1.0 && f[3] > 0.5, "{f:?}");
        // Half the points voting find the same circle, its coverage counted with all of them.
        let half = find_circles(
            &pts,
            &CircleSearch {
                vote_every: 2,
                ..search()
            },
        );
        assert_eq!(half.first(), Some(&f), "{half:?}");
    }

    #[test]
    fn a_rim_overflowing_the_image_is_covered_over_its_visible_part() {
        // Centre 20 px above the bottom of a 120 px image, radius 40: the rim below the image
        // (a third of it) cannot have edges; blades hide half of the rest. 120° of edges: a
        // third of the whole rim (below `min_coverage` 0.4), half of the visible part.
        let (c, r) = ([60.0, 100.0], 40.0);
        let pts = rim_points(c, r, &[(160.0, 220.0), (260.0, 320.0)]);
        assert!(pts.iter().all(|e| e.p[1] < 120.0));
        let cs = CircleSearch {
            max_r: 45.0,
            ..search()
        };
        assert!(find_circles(&pts, &cs)
            .iter()
            .all(|f| (f[2] - r).abs() > 2.0));
        let seen = find_circles(
            &pts,
            &CircleSearch {
                visible_in: Some([120.0, 120.0]),
                ..cs
            },
        );
        let f = seen.first().expect("found on its visible part");
        assert!(crate::geometry::dist([f[0], f[1]], c) < 1.5, "{f:?}");
        assert!(
            (f[2] - r).abs() < 1.5 && (0.4..0.6).contains(&f[3]),
            "{f:?}"
        );
        // The visible share is bounded below: an arc in a corner stays a small part of a rim.
        assert_eq!(
            visible_rim([0.0, 0.0], 50.0, [120.0, 120.0]),
            MIN_VISIBLE_RIM
        );
        assert!((visible_rim(c, r, [120.0, 120.0]) - 2.0 / 3.0).abs() < 0.03);
        assert_eq!(visible_rim([60.0, 60.0], 30.0, [120.0, 120.0]), 1.0);
    }

    #[test]
    fn lines_and_sparse_arcs_are_rejected() {
        // Two crossing straight edges: no rim.
        let mut pts: Vec<EdgePoint> = (0..100)
            .map(|k| EdgePoint {
                p: [10.0 + k as f64, 60.0],
                u: [0.0, 1.0],
            })
            .collect();
        pts.extend((0..100).map(|k| EdgePoint {
            p: [60.0, 10.0 + k as f64],
            u: [1.0, 0.0],
        }));
        assert!(find_circles(&pts, &search()).is_empty());
        // A 60° arc covers a sixth of its rim: below min_coverage.
        let arc = rim_points([60.0, 60.0], 25.0, &[(0.0, 60.0)]);
        assert!(find_circles(&arc, &search()).is_empty());
    }

    #[test]
    fn a_rim_around_clutter_is_no_spinner() {
        let c = [60.0, 60.0];
        let rim = rim_points(c, 20.0, &[(0.0, 360.0)]);
        assert_eq!(find_circles(&rim, &search()).len(), 1);
        // The same rim with a textured inside (an edge pixel every 3 px each way, gradients
        // pointing anywhere): clutter that happens to contain a ring of edges.
        let mut cluttered = rim.clone();
        for y in (46..75).step_by(3) {
            for x in (46..75).step_by(3) {
                let t = ((x * 7 + y * 13) % 360) as f64;
                cluttered.push(EdgePoint {
                    p: [x as f64, y as f64],
                    u: [t.to_radians().cos(), t.to_radians().sin()],
                });
            }
        }
        let inner = (INNER_FRAC * 20.0_f64).powi(2) * std::f64::consts::PI;
        let inside = cluttered
            .iter()
            .filter(|e| crate::geometry::dist(e.p, c).powi(2) < (INNER_FRAC * 20.0_f64).powi(2))
            .count();
        assert!(
            inside as f64 > search().max_interior_density * inner,
            "the clutter must exceed the limit"
        );
        assert!(find_circles(&cluttered, &search())
            .iter()
            .all(|f| crate::geometry::dist([f[0], f[1]], c) > 2.0));
    }

    #[test]
    fn kasa_fit_is_exact_on_a_circle() {
        let pts: Vec<P2> = (0..12)
            .map(|k| {
                let t = (k as f64 * 30.0).to_radians();
                [5.0 + 7.0 * t.cos(), -3.0 + 7.0 * t.sin()]
            })
            .collect();
        let f = fit_circle(&pts).unwrap();
        assert!(
            (f[0] - 5.0).abs() < 1e-9 && (f[1] + 3.0).abs() < 1e-9 && (f[2] - 7.0).abs() < 1e-9,
            "{f:?}"
        );
    }
}
