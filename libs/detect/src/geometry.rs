//! Plain 2D geometry over line segments: angles, intersections, grouping by angle, the thesis's
//! 120° voting and intersection filtering. No OpenCV here, so every step is unit-testable on
//! constructed line sets.
//!
//! Image coordinates: x right, y **down**, pixel centres at integer coordinates. Directions are
//! given as "up-clockwise" angles in degrees: 0 = straight up in the image, 90 = right,
//! 180 = down, 270 = left (the convention of `Detection::blade_angles_deg`).

/// A 2D point `[x, y]` in pixels.
pub type P2 = [f64; 2];

/// A straight line segment between two pixel points.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Segment {
    /// First end point.
    pub a: P2,
    /// Second end point.
    pub b: P2,
}

impl Segment {
    /// Segment from `a` to `b`.
    pub const fn new(a: P2, b: P2) -> Segment {
        Segment { a, b }
    }

    /// Euclidean length, px.
    pub fn length(&self) -> f64 {
        dist(self.a, self.b)
    }

    /// Mid point.
    pub fn midpoint(&self) -> P2 {
        [(self.a[0] + self.b[0]) * 0.5, (self.a[1] + self.b[1]) * 0.5]
    }

    /// Undirected tilt from the image vertical in degrees, in (−90, 90]: 0 = vertical, positive
    /// when the upper end leans to the right (clockwise from up).
    pub fn tilt_from_vertical_deg(&self) -> f64 {
        let (top, bottom) = if self.a[1] <= self.b[1] {
            (self.a, self.b)
        } else {
            (self.b, self.a)
        };
        let a = up_cw_deg([top[0] - bottom[0], top[1] - bottom[1]]);
        // a is in [0, 90] ∪ [270, 360) (upward direction) or exactly 90/270 for horizontals.
        let t = wrap180(a);
        if t <= -90.0 {
            t + 180.0
        } else {
            t
        }
    }

    /// Undirected orientation in [0, 180) degrees, up-clockwise (0 = vertical, 90 = horizontal).
    pub fn orientation_deg(&self) -> f64 {
        let a = up_cw_deg([self.b[0] - self.a[0], self.b[1] - self.a[1]]);
        a % 180.0
    }

    /// The end point nearer to `p` and its distance.
    pub fn nearest_end(&self, p: P2) -> (P2, f64) {
        let (da, db) = (dist(self.a, p), dist(self.b, p));
        if da <= db {
            (self.a, da)
        } else {
            (self.b, db)
        }
    }

    /// Direction angle (up-clockwise, [0, 360)) pointing from the end nearer to `p` toward the
    /// far end: the direction in which a blade "beams out" from a hub at `p`.
    pub fn angle_away_from(&self, p: P2) -> f64 {
        let (near, far) = if dist(self.a, p) <= dist(self.b, p) {
            (self.a, self.b)
        } else {
            (self.b, self.a)
        };
        up_cw_deg([far[0] - near[0], far[1] - near[1]])
    }

    /// x of the infinite line through the segment at row `y`; `None` for (near) horizontal lines.
    pub fn x_at_y(&self, y: f64) -> Option<f64> {
        let dy = self.b[1] - self.a[1];
        if dy.abs() < 1e-9 {
            return None;
        }
        Some(self.a[0] + (y - self.a[1]) * (self.b[0] - self.a[0]) / dy)
    }

    /// Perpendicular distance from `p` to the infinite line through the segment.
    pub fn line_distance(&self, p: P2) -> f64 {
        let (dx, dy) = (self.b[0] - self.a[0], self.b[1] - self.a[1]);
        let len = (dx * dx + dy * dy).sqrt();
        if len < 1e-12 {
            return dist(self.a, p);
        }
        ((p[0] - self.a[0]) * dy - (p[1] - self.a[1]) * dx).abs() / len
    }

    /// Distance from `p` to the closest point of the segment.
    pub fn segment_distance(&self, p: P2) -> f64 {
        let (dx, dy) = (self.b[0] - self.a[0], self.b[1] - self.a[1]);
        let l2 = dx * dx + dy * dy;
        if l2 < 1e-12 {
            return dist(self.a, p);
        }
        let t = (((p[0] - self.a[0]) * dx + (p[1] - self.a[1]) * dy) / l2).clamp(0.0, 1.0);
        dist([self.a[0] + t * dx, self.a[1] + t * dy], p)
    }

    /// Position of the projection of `p` on the line, as a fraction of the segment (0 at `a`,
    /// 1 at `b`).
    pub fn project_t(&self, p: P2) -> f64 {
        let (dx, dy) = (self.b[0] - self.a[0], self.b[1] - self.a[1]);
        let l2 = (dx * dx + dy * dy).max(1e-12);
        ((p[0] - self.a[0]) * dx + (p[1] - self.a[1]) * dy) / l2
    }

    /// Both end points multiplied by `k` (pyramid level to full resolution: `k = 2^levels`,
    /// because `pyrDown` centres destination pixel `i` on source pixel `2i`).
    pub fn scaled(&self, k: f64) -> Segment {
        Segment {
            a: scale_point(self.a, k),
            b: scale_point(self.b, k),
        }
    }
}

/// Point multiplied by `k` (see [`Segment::scaled`]).
pub fn scale_point(p: P2, k: f64) -> P2 {
    [p[0] * k, p[1] * k]
}

/// Euclidean distance.
pub fn dist(a: P2, b: P2) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)).sqrt()
}

/// Up-clockwise angle of an image vector (y down), degrees in [0, 360).
pub fn up_cw_deg(v: P2) -> f64 {
    let a = v[0].atan2(-v[1]).to_degrees();
    if a < 0.0 {
        a + 360.0
    } else {
        a
    }
}

/// Unit image vector for an up-clockwise angle.
pub fn dir_from_up_cw(deg: f64) -> P2 {
    let r = deg.to_radians();
    [r.sin(), -r.cos()]
}

/// Wrap an angle to (−180, 180].
pub fn wrap180(a: f64) -> f64 {
    let mut r = a % 360.0;
    if r <= -180.0 {
        r += 360.0;
    } else if r > 180.0 {
        r -= 360.0;
    }
    r
}

/// Wrap an angle to [0, 360).
pub fn wrap360(a: f64) -> f64 {
    let r = a % 360.0;
    if r < 0.0 {
        r + 360.0
    } else {
        r
    }
}

/// Absolute smallest difference between two directions, degrees in [0, 180].
pub fn ang_dist(a: f64, b: f64) -> f64 {
    wrap180(a - b).abs()
}

/// How far a direction (degrees, any convention whose axes are multiples of 90°) lies from the
/// nearest image axis, vertical or horizontal: degrees in [0, 45].
pub fn off_axes_deg(a: f64) -> f64 {
    let r = a.rem_euclid(90.0);
    r.min(90.0 - r)
}

/// Tilt of a segment from the *world* vertical, given the camera roll (clockwise positive, which
/// makes the image content appear rotated counter-clockwise by the same angle). Degrees in
/// (−90, 90].
pub fn roll_compensated_tilt_deg(s: &Segment, roll_deg: f64) -> f64 {
    let t = s.tilt_from_vertical_deg() + roll_deg;
    let w = wrap180(t);
    if w > 90.0 {
        w - 180.0
    } else if w <= -90.0 {
        w + 180.0
    } else {
        w
    }
}

/// Intersection of the infinite lines through two segments; `None` when (nearly) parallel.
pub fn line_intersection(s: &Segment, t: &Segment) -> Option<P2> {
    let (r, q) = (
        [s.b[0] - s.a[0], s.b[1] - s.a[1]],
        [t.b[0] - t.a[0], t.b[1] - t.a[1]],
    );
    let den = r[0] * q[1] - r[1] * q[0];
    let norm = (r[0].hypot(r[1]) * q[0].hypot(q[1])).max(1e-12);
    // sin of the angle between the lines below ~0.06° means parallel for any practical purpose.
    if (den / norm).abs() < 1e-3 {
        return None;
    }
    let w = [t.a[0] - s.a[0], t.a[1] - s.a[1]];
    let u = (w[0] * q[1] - w[1] * q[0]) / den;
    Some([s.a[0] + u * r[0], s.a[1] + u * r[1]])
}

/// Circular (weighted) mean of directions in degrees, [0, 360). Returns 0 for empty input.
pub fn circular_mean_deg(angles: &[f64], weights: Option<&[f64]>) -> f64 {
    let (mut sx, mut sy) = (0.0, 0.0);
    for (i, a) in angles.iter().enumerate() {
        let w = weights.map_or(1.0, |w| w[i]);
        let r = a.to_radians();
        sx += w * r.sin();
        sy += w * r.cos();
    }
    wrap360(sx.atan2(sy).to_degrees())
}

/// Group directions (degrees) into clusters of adjacent angles: sorted around the circle,
/// neighbours closer than `tol_deg` chain into one group (single linkage, wrapping at 360°).
/// Returns index lists into `angles`.
pub fn group_by_angle(angles: &[f64], tol_deg: f64) -> Vec<Vec<usize>> {
    let n = angles.len();
    if n == 0 {
        return Vec::new();
    }
    let mut idx: Vec<usize> = (0..n).collect();
    idx.sort_by(|&i, &j| wrap360(angles[i]).total_cmp(&wrap360(angles[j])));
    // Start the chain after the largest circular gap so that a cluster straddling 0° is not split.
    let gap = |k: usize| -> f64 {
        if n == 1 {
            return 360.0;
        }
        let (a, b) = (wrap360(angles[idx[k]]), wrap360(angles[idx[(k + 1) % n]]));
        if k == n - 1 {
            b + 360.0 - a
        } else {
            b - a
        }
    };
    let last = (0..n)
        .max_by(|&i, &j| gap(i).total_cmp(&gap(j)))
        .unwrap_or(n - 1);
    let start = (last + 1) % n;
    let mut groups: Vec<Vec<usize>> = Vec::new();
    let mut cur = vec![idx[start]];
    for step in 1..n {
        let prev = idx[(start + step - 1) % n];
        let this = idx[(start + step) % n];
        if wrap360(angles[this] - angles[prev]) <= tol_deg {
            cur.push(this);
        } else {
            groups.push(std::mem::take(&mut cur));
            cur.push(this);
        }
    }
    groups.push(cur);
    groups
}

/// The thesis's pairwise voting (section 6.1.5.2): every pair of blades whose angular separation
/// is not within `tol_deg` of `target_deg` gives both blades a vote; blades with at least
/// `vote_limit` votes are false. Returns the votes per blade.
pub fn vote_pairwise(angles: &[f64], target_deg: f64, tol_deg: f64) -> Vec<u32> {
    let mut votes = vec![0u32; angles.len()];
    for i in 0..angles.len() {
        for j in i + 1..angles.len() {
            if (ang_dist(angles[i], angles[j]) - target_deg).abs() > tol_deg {
                votes[i] += 1;
                votes[j] += 1;
            }
        }
    }
    votes
}

/// Which blades survive the vote (`votes < vote_limit`).
pub fn vote_keep(angles: &[f64], target_deg: f64, tol_deg: f64, vote_limit: u32) -> Vec<bool> {
    vote_pairwise(angles, target_deg, tol_deg)
        .into_iter()
        .map(|v| v < vote_limit)
        .collect()
}

/// Keep the points that lie within `max_dx` horizontally of the (infinite) tower axis line at
/// their own row and within `max_dy` vertically of `ref_point` (the thesis's temporary hub
/// estimate, the tower top). Returns the kept points.
pub fn filter_intersections(
    points: &[P2],
    axis: &Segment,
    ref_point: P2,
    max_dx: f64,
    max_dy: f64,
) -> Vec<P2> {
    points
        .iter()
        .copied()
        .filter(|p| {
            let ax = axis.x_at_y(p[1]).unwrap_or(ref_point[0]);
            (p[0] - ax).abs() <= max_dx && (p[1] - ref_point[1]).abs() <= max_dy
        })
        .collect()
}

/// Arithmetic mean of points; `None` if empty.
pub fn mean_point(points: &[P2]) -> Option<P2> {
    if points.is_empty() {
        return None;
    }
    let n = points.len() as f64;
    let s = points
        .iter()
        .fold([0.0, 0.0], |s, p| [s[0] + p[0], s[1] + p[1]]);
    Some([s[0] / n, s[1] / n])
}

/// Median of a slice (sorted copy); `None` if empty.
pub fn median(v: &[f64]) -> Option<f64> {
    if v.is_empty() {
        return None;
    }
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    let m = s.len() / 2;
    Some(if s.len() % 2 == 1 {
        s[m]
    } else {
        0.5 * (s[m - 1] + s[m])
    })
}

/// Distance from `p` to the segment `a`–`b` (used for scoring against the hub→nose segment).
pub fn point_segment_distance(p: P2, a: P2, b: P2) -> f64 {
    Segment::new(a, b).segment_distance(p)
}

/// Two edges further apart in direction than this (degrees) bound no band in [`band_axis`].
pub const BAND_MAX_ANGLE_DEG: f64 = 45.0;

/// Unit normal `n` and offset `c` of the infinite line through a segment (points `q` on it satisfy
/// `n·q = c`); `None` for a degenerate segment.
pub fn line_normal(s: &Segment) -> Option<(P2, f64)> {
    let len = s.length();
    if len < 1e-9 {
        return None;
    }
    let n = [-(s.b[1] - s.a[1]) / len, (s.b[0] - s.a[0]) / len];
    Some((n, n[0] * s.a[0] + n[1] * s.a[1]))
}

/// Axis of the band between two edges `s`, `t` (the two edges of a blade or of the tower): the
/// internal angle bisector, i.e. the points between the two lines at equal distance from both.
/// With the normals oriented alike (`n_s·n_t > 0`) it is `(n_s + n_t)·q = c_s + c_t`. Returned as
/// the segment spanning the projections of all four end points onto it, ordered like `s`.
/// `None` for degenerate edges or edges more than [`BAND_MAX_ANGLE_DEG`] apart.
pub fn band_axis(s: &Segment, t: &Segment) -> Option<Segment> {
    let (ns, cs) = line_normal(s)?;
    let (mut nt, mut ct) = line_normal(t)?;
    if ns[0] * nt[0] + ns[1] * nt[1] < 0.0 {
        nt = [-nt[0], -nt[1]];
        ct = -ct;
    }
    let m = [ns[0] + nt[0], ns[1] + nt[1]];
    let ml = m[0].hypot(m[1]);
    // |n_s + n_t| = 2 cos(θ/2) for edges θ apart: beyond BAND_MAX_ANGLE_DEG there is no band.
    if ml < 2.0 * (0.5 * BAND_MAX_ANGLE_DEG).to_radians().cos() {
        return None;
    }
    let (n, c) = ([m[0] / ml, m[1] / ml], (cs + ct) / ml);
    // Direction along the axis, oriented like s (a -> b).
    let mut d = [n[1], -n[0]];
    if d[0] * (s.b[0] - s.a[0]) + d[1] * (s.b[1] - s.a[1]) < 0.0 {
        d = [-d[0], -d[1]];
    }
    let foot = [n[0] * c, n[1] * c];
    let along = |q: P2| (q[0] - foot[0]) * d[0] + (q[1] - foot[1]) * d[1];
    let ts = [along(s.a), along(s.b), along(t.a), along(t.b)];
    let lo = ts.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = ts.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let at = |u: f64| [foot[0] + u * d[0], foot[1] + u * d[1]];
    Some(Segment::new(at(lo), at(hi)))
}

/// Width of the band between the lines through `s` and `t`, measured across at point `q` (sum
/// of the distances from `q` to both lines; `q` between them, e.g. on their [`band_axis`]).
pub fn band_width_at(s: &Segment, t: &Segment, q: P2) -> f64 {
    s.line_distance(q) + t.line_distance(q)
}

/// Length of the overlap of `t`'s projection onto `s`'s line with `s` itself, px.
pub fn projected_overlap(s: &Segment, t: &Segment) -> f64 {
    let len = s.length();
    let (ta, tb) = (s.project_t(t.a), s.project_t(t.b));
    let (lo, hi) = (ta.min(tb).max(0.0), ta.max(tb).min(1.0));
    (hi - lo).max(0.0) * len
}

/// Weighted least-squares point nearest to all the infinite lines through `lines`; `None` when
/// the lines are (nearly) all parallel or fewer than two.
pub fn lines_nearest_point(lines: &[(Segment, f64)]) -> Option<P2> {
    let (mut a11, mut a12, mut a22, mut b1, mut b2) = (0.0, 0.0, 0.0, 0.0, 0.0);
    for (s, w) in lines {
        let Some((n, c)) = line_normal(s) else {
            continue;
        };
        a11 += w * n[0] * n[0];
        a12 += w * n[0] * n[1];
        a22 += w * n[1] * n[1];
        b1 += w * n[0] * c;
        b2 += w * n[1] * c;
    }
    let det = a11 * a22 - a12 * a12;
    // Relative to the total weight squared: below this the lines are almost parallel.
    let wsum = a11 + a22;
    if wsum <= 0.0 || det / (wsum * wsum) < 1e-4 {
        return None;
    }
    Some([(a22 * b1 - a12 * b2) / det, (a11 * b2 - a12 * b1) / det])
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: f64, b: f64, eps: f64) -> bool {
        (a - b).abs() <= eps
    }

    #[test]
    fn angles_up_clockwise() {
        assert!(close(up_cw_deg([0.0, -1.0]), 0.0, 1e-9));
        assert!(close(up_cw_deg([1.0, 0.0]), 90.0, 1e-9));
        assert!(close(up_cw_deg([0.0, 1.0]), 180.0, 1e-9));
        assert!(close(up_cw_deg([-1.0, 0.0]), 270.0, 1e-9));
        let d = dir_from_up_cw(135.0);
        assert!(close(up_cw_deg(d), 135.0, 1e-9));
    }

    #[test]
    fn tilt_and_roll_compensation() {
        // A line leaning right at the top by 8°.
        let d = dir_from_up_cw(8.0);
        let s = Segment::new([100.0, 200.0], [100.0 + 100.0 * d[0], 200.0 + 100.0 * d[1]]);
        assert!(close(s.tilt_from_vertical_deg(), 8.0, 1e-9));
        // Reversed end points: same undirected tilt.
        let r = Segment::new(s.b, s.a);
        assert!(close(r.tilt_from_vertical_deg(), 8.0, 1e-9));
        // A camera rolled clockwise by 8° shows a world-vertical tower rotated counter-clockwise by 8°:
        // the image line leaning left by 8° is world-vertical.
        let d = dir_from_up_cw(-8.0);
        let left = Segment::new([0.0, 100.0], [100.0 * d[0], 100.0 + 100.0 * d[1]]);
        assert!(close(roll_compensated_tilt_deg(&left, 8.0), 0.0, 1e-9));
        assert!(close(roll_compensated_tilt_deg(&left, 0.0), -8.0, 1e-9));
        // Near-horizontal stays near ±90 and wraps.
        let h = Segment::new([0.0, 0.0], [100.0, 1.0]);
        assert!(roll_compensated_tilt_deg(&h, 5.0).abs() > 80.0);
    }

    #[test]
    fn intersection_of_lines() {
        let s = Segment::new([0.0, 0.0], [10.0, 10.0]);
        let t = Segment::new([0.0, 10.0], [10.0, 0.0]);
        let p = line_intersection(&s, &t).unwrap();
        assert!(close(p[0], 5.0, 1e-9) && close(p[1], 5.0, 1e-9));
        let par = Segment::new([0.0, 1.0], [10.0, 11.0]);
        assert!(line_intersection(&s, &par).is_none());
    }

    #[test]
    fn grouping_wraps_around_zero() {
        let angles = [355.0, 3.0, 118.0, 122.0, 125.0, 241.0];
        let mut groups = group_by_angle(&angles, 10.0);
        groups.iter_mut().for_each(|g| g.sort());
        groups.sort();
        assert_eq!(groups, vec![vec![0, 1], vec![2, 3, 4], vec![5]]);
        let m = circular_mean_deg(&[355.0, 3.0], None);
        assert!(close(wrap180(m), -1.0, 1e-9), "{m}");
        assert_eq!(group_by_angle(&[42.0], 5.0), vec![vec![0]]);
        assert!(group_by_angle(&[], 5.0).is_empty());
    }

    #[test]
    fn voting_removes_false_blade() {
        // Three true blades at 120° spacing plus a horizon-like false blade at 270°.
        let angles = [10.0, 130.0, 250.0, 300.0];
        let keep = vote_keep(&angles, 120.0, 20.0, 3);
        assert_eq!(keep, vec![true, true, true, false]);
        assert_eq!(vote_pairwise(&angles, 120.0, 20.0), vec![1, 1, 1, 3]);
    }

    #[test]
    fn intersection_filter_drops_horizon_point() {
        let axis = Segment::new([200.0, 300.0], [200.0, 100.0]);
        let top = [200.0, 100.0];
        let pts = [[203.0, 90.0], [197.0, 95.0], [320.0, 98.0], [201.0, 180.0]];
        let kept = filter_intersections(&pts, &axis, top, 20.0, 40.0);
        assert_eq!(kept, vec![[203.0, 90.0], [197.0, 95.0]]);
    }

    #[test]
    fn scaling_to_full_resolution() {
        // Two pyrDown levels: small px i is centred on full-res px 4i.
        let s = Segment::new([10.0, 20.0], [30.5, 40.0]).scaled(4.0);
        assert_eq!(s, Segment::new([40.0, 80.0], [122.0, 160.0]));
    }

    #[test]
    fn segment_helpers() {
        let s = Segment::new([0.0, 0.0], [0.0, 100.0]);
        assert!(close(s.x_at_y(50.0).unwrap(), 0.0, 1e-12));
        assert!(close(s.line_distance([3.0, 500.0]), 3.0, 1e-12));
        assert!(close(s.segment_distance([3.0, 104.0]), 5.0, 1e-12));
        assert!(close(s.angle_away_from([0.0, -5.0]), 180.0, 1e-9));
        assert!(close(
            point_segment_distance([0.0, 0.0], [3.0, 4.0], [3.0, 10.0]),
            5.0,
            1e-12
        ));
        assert_eq!(median(&[3.0, 1.0, 2.0]), Some(2.0));
    }

    #[test]
    fn band_axis_is_the_bisector_of_converging_edges() {
        // A blade pointing right from x = 100, root width 20 (y 90..110), tip width 4 at x = 300.
        let upper = Segment::new([100.0, 90.0], [300.0, 98.0]);
        let lower = Segment::new([300.0, 102.0], [100.0, 110.0]);
        let ax = band_axis(&upper, &lower).unwrap();
        // Axis along y = 100, spanning x 100..300, ordered like `upper`.
        assert!(
            close(ax.a[1], 100.0, 1e-6) && close(ax.b[1], 100.0, 1e-6),
            "{ax:?}"
        );
        assert!(
            close(ax.a[0], 100.0, 0.5) && close(ax.b[0], 300.0, 0.5),
            "{ax:?}"
        );
        assert!(close(
            band_width_at(&upper, &lower, [100.0, 100.0]),
            20.0,
            0.1
        ));
        assert!(close(
            band_width_at(&upper, &lower, [300.0, 100.0]),
            4.0,
            0.1
        ));
        // Perpendicular edges form no band.
        assert!(band_axis(
            &Segment::new([0.0, 0.0], [10.0, 0.0]),
            &Segment::new([0.0, 0.0], [0.0, 10.0])
        )
        .is_none());
    }

    #[test]
    fn overlap_and_nearest_point_of_lines() {
        let s = Segment::new([0.0, 0.0], [100.0, 0.0]);
        assert!(close(
            projected_overlap(&s, &Segment::new([50.0, 5.0], [150.0, 5.0])),
            50.0,
            1e-9
        ));
        assert!(close(
            projected_overlap(&s, &Segment::new([150.0, 5.0], [250.0, 5.0])),
            0.0,
            1e-9
        ));
        let hub = [200.0, 120.0];
        let lines: Vec<(Segment, f64)> = [10.0, 130.0, 250.0]
            .iter()
            .map(|&a| {
                let d = dir_from_up_cw(a);
                (
                    Segment::new(
                        [hub[0] + 30.0 * d[0], hub[1] + 30.0 * d[1]],
                        [hub[0] + 90.0 * d[0], hub[1] + 90.0 * d[1]],
                    ),
                    1.0,
                )
            })
            .collect();
        let p = lines_nearest_point(&lines).unwrap();
        assert!(dist(p, hub) < 1e-6, "{p:?}");
        assert!(lines_nearest_point(&lines[..1]).is_none());
    }
}
