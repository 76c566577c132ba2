//! Reference-line geometry of OpenDRIVE plan views: line, arc, spiral (clothoid), poly3 and paramPoly3
//! records evaluated to a world position and heading at a distance along the record, plus the cubic
//! polynomials (`a + b ds + c ds² + d ds³`) used by elevation, lane offsets and lane widths.
//!
//! The clothoid is evaluated by integrating its heading θ(s) = k0 s + c s²/2 with composite 5-point
//! Gauss–Legendre quadrature over ≤ 1 m sub-intervals, i.e. the Fresnel integrals evaluated numerically; the
//! error is below 1e-6 m for curvatures found in road design (checked against reference Fresnel values).
//! poly3 is parameterised by arc length by Newton iteration on its arc-length integral.

use glam::DVec2;

/// The shape of one `<geometry>` record.
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum GeomKind {
    Line,
    Arc { curvature: f64 },
    Spiral { curv_start: f64, curv_end: f64 },
    Poly3 { a: f64, b: f64, c: f64, d: f64 },
    ParamPoly3 { u: [f64; 4], v: [f64; 4], normalized: bool },
}

/// One `<geometry>` record of a plan view.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Geometry {
    pub s: f64,
    pub x: f64,
    pub y: f64,
    pub hdg: f64,
    pub length: f64,
    pub kind: GeomKind,
    /// Byte offset of the element in the source.
    pub pos: u32,
}

const GL_X: [f64; 5] = [
    -0.906_179_845_938_664,
    -0.538_469_310_105_683,
    0.0,
    0.538_469_310_105_683,
    0.906_179_845_938_664,
];
const GL_W: [f64; 5] = [
    0.236_926_885_056_189,
    0.478_628_670_499_366,
    0.568_888_888_888_889,
    0.478_628_670_499_366,
    0.236_926_885_056_189,
];

/// ∫_0^len f(x) dx by composite 5-point Gauss–Legendre over sub-intervals of at most `max_step`.
fn integrate(len: f64, max_step: f64, mut f: impl FnMut(f64) -> DVec2) -> DVec2 {
    if len <= 0.0 {
        return DVec2::ZERO;
    }
    let n = ((len / max_step).ceil() as usize).clamp(1, 10_000);
    let h = len / n as f64;
    let mut acc = DVec2::ZERO;
    for i in 0..n {
        let mid = (i as f64 + 0.5) * h;
        for k in 0..5 {
            acc += f(mid + GL_X[k] * h * 0.5) * (GL_W[k] * h * 0.5);
        }
    }
    acc
}

fn cubic(c: &[f64; 4], p: f64) -> f64 {
    c[0] + p * (c[1] + p * (c[2] + p * c[3]))
}

fn cubic_d(c: &[f64; 4], p: f64) -> f64 {
    c[1] + p * (2.0 * c[2] + p * 3.0 * c[3])
}

impl Geometry {
    /// Local position (u along the start heading, v to its left) and local heading at `ds` ∈ [0, length].
    fn local(&self, ds: f64) -> (DVec2, f64) {
        match self.kind {
            GeomKind::Line => (DVec2::new(ds, 0.0), 0.0),
            GeomKind::Arc { curvature: k } => {
                if k.abs() < 1e-12 {
                    (DVec2::new(ds, 0.0), 0.0)
                } else {
                    let a = k * ds;
                    (DVec2::new(a.sin() / k, (1.0 - a.cos()) / k), a)
                }
            }
            GeomKind::Spiral {
                curv_start: k0,
                curv_end: k1,
            } => {
                let c = if self.length > 0.0 {
                    (k1 - k0) / self.length
                } else {
                    0.0
                };
                let theta = |s: f64| k0 * s + 0.5 * c * s * s;
                let p = integrate(ds, 1.0, |s| {
                    let (sn, cs) = theta(s).sin_cos();
                    DVec2::new(cs, sn)
                });
                (p, theta(ds))
            }
            GeomKind::Poly3 { a, b, c, d } => {
                let coef = [a, b, c, d];
                let arclen =
                    |u: f64| integrate(u, 2.0, |x| DVec2::new((1.0 + cubic_d(&coef, x).powi(2)).sqrt(), 0.0)).x;
                let mut u = ds;
                for _ in 0..8 {
                    let err = arclen(u) - ds;
                    let dsdu = (1.0 + cubic_d(&coef, u).powi(2)).sqrt();
                    let next = u - err / dsdu;
                    if !next.is_finite() {
                        break;
                    }
                    u = next.max(0.0);
                    if err.abs() < 1e-9 {
                        break;
                    }
                }
                (DVec2::new(u, cubic(&coef, u)), cubic_d(&coef, u).atan())
            }
            GeomKind::ParamPoly3 { u, v, normalized } => {
                let p = if normalized {
                    if self.length > 0.0 { ds / self.length } else { 0.0 }
                } else {
                    ds
                };
                let du = cubic_d(&u, p);
                let dv = cubic_d(&v, p);
                let h = if du == 0.0 && dv == 0.0 { 0.0 } else { dv.atan2(du) };
                (DVec2::new(cubic(&u, p), cubic(&v, p)), h)
            }
        }
    }

    /// World position and heading at `ds` metres from the start of the record (clamped to its length).
    pub(crate) fn eval(&self, ds: f64) -> (DVec2, f64) {
        let ds = ds.clamp(0.0, self.length);
        let (l, h) = self.local(ds);
        let (sn, cs) = self.hdg.sin_cos();
        (
            DVec2::new(self.x + cs * l.x - sn * l.y, self.y + sn * l.x + cs * l.y),
            self.hdg + h,
        )
    }

    /// The length of the polyline through `n + 1` evenly spaced points of the record (at most its arc length):
    /// a record whose curve is much longer than its declared `length` is malformed.
    pub(crate) fn traced_length(&self, n: usize) -> f64 {
        let step = self.length / n.max(1) as f64;
        let mut prev = self.eval(0.0).0;
        (1..=n.max(1))
            .map(|i| {
                let p = self.eval(step * i as f64).0;
                let d = p.distance(prev);
                prev = p;
                d
            })
            .sum()
    }

    /// An upper estimate of |curvature| over the record, used to choose the station spacing.
    pub(crate) fn max_curvature(&self) -> f64 {
        match self.kind {
            GeomKind::Line => 0.0,
            GeomKind::Arc { curvature } => curvature.abs(),
            GeomKind::Spiral { curv_start, curv_end } => curv_start.abs().max(curv_end.abs()),
            GeomKind::Poly3 { .. } | GeomKind::ParamPoly3 { .. } => {
                let n = 16;
                let mut prev = self.eval(0.0).1;
                let mut k: f64 = 0.0;
                let h = self.length / n as f64;
                if h <= 0.0 {
                    return 0.0;
                }
                for i in 1..=n {
                    let cur = self.eval(h * i as f64).1;
                    k = k.max(wrap_angle(cur - prev).abs() / h);
                    prev = cur;
                }
                k
            }
        }
    }
}

/// Wraps an angle to (-π, π].
pub(crate) fn wrap_angle(a: f64) -> f64 {
    let t = std::f64::consts::TAU;
    let mut r = a % t;
    if r > std::f64::consts::PI {
        r -= t;
    } else if r <= -std::f64::consts::PI {
        r += t;
    }
    r
}

/// A cubic polynomial record starting at `s` (elevation, lane offset, lane width: `s` is `sOffset` there).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Poly3At {
    pub s: f64,
    pub c: [f64; 4],
    /// Byte offset of the element in the source.
    pub pos: u32,
}

/// Evaluates a piecewise cubic (records sorted by `s`) at `s`; 0 before the first record or if empty.
pub(crate) fn eval_piecewise(records: &[Poly3At], s: f64) -> f64 {
    let idx = records.partition_point(|r| r.s <= s + 1e-9);
    if idx == 0 {
        return match records.first() {
            Some(r) => r.c[0],
            None => 0.0,
        };
    }
    let r = &records[idx - 1];
    cubic(&r.c, s - r.s)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn geom(kind: GeomKind, length: f64) -> Geometry {
        Geometry {
            s: 0.0,
            x: 1.0,
            y: 2.0,
            hdg: 0.5,
            length,
            kind,
            pos: 0,
        }
    }

    #[test]
    fn arc_quarter_circle() {
        let g = Geometry {
            hdg: 0.0,
            x: 0.0,
            y: 0.0,
            ..geom(GeomKind::Arc { curvature: 0.1 }, 5.0 * std::f64::consts::PI)
        };
        let (p, h) = g.eval(g.length);
        assert!((p - DVec2::new(10.0, 10.0)).length() < 1e-9, "{p}");
        assert!((h - std::f64::consts::FRAC_PI_2).abs() < 1e-12);
    }

    #[test]
    fn spiral_with_constant_curvature_matches_arc() {
        let a = geom(GeomKind::Arc { curvature: 0.05 }, 30.0);
        let s = geom(
            GeomKind::Spiral {
                curv_start: 0.05,
                curv_end: 0.05,
            },
            30.0,
        );
        for ds in [0.0, 3.3, 17.0, 30.0] {
            let (pa, ha) = a.eval(ds);
            let (ps, hs) = s.eval(ds);
            assert!((pa - ps).length() < 1e-9 && (ha - hs).abs() < 1e-12);
        }
    }

    #[test]
    fn clothoid_matches_fresnel_reference() {
        // Unit clothoid k(s) = s (A = 1): x(√π) = √π·C(1), y = √π·S(1) with C(1)=0.7798934, S(1)=0.4382591.
        let l = std::f64::consts::PI.sqrt();
        let g = Geometry {
            x: 0.0,
            y: 0.0,
            hdg: 0.0,
            ..geom(
                GeomKind::Spiral {
                    curv_start: 0.0,
                    curv_end: l,
                },
                l,
            )
        };
        let (p, _) = g.eval(l);
        assert!((p.x - l * 0.779_893_400_376_823).abs() < 1e-6, "{p}");
        assert!((p.y - l * 0.438_259_147_390_355).abs() < 1e-6, "{p}");
    }

    #[test]
    fn straight_poly3_and_param_poly3() {
        let p3 = geom(
            GeomKind::Poly3 {
                a: 0.0,
                b: 0.0,
                c: 0.0,
                d: 0.0,
            },
            10.0,
        );
        let pp = geom(
            GeomKind::ParamPoly3 {
                u: [0.0, 10.0, 0.0, 0.0],
                v: [0.0; 4],
                normalized: true,
            },
            10.0,
        );
        let l = geom(GeomKind::Line, 10.0);
        for ds in [0.0, 4.0, 10.0] {
            assert!((p3.eval(ds).0 - l.eval(ds).0).length() < 1e-9);
            assert!((pp.eval(ds).0 - l.eval(ds).0).length() < 1e-9);
        }
        // A curved poly3 keeps arc length: the end point lies on the curve at the right distance.
        let c = Geometry {
            hdg: 0.0,
            x: 0.0,
            y: 0.0,
            ..geom(
                GeomKind::Poly3 {
                    a: 0.0,
                    b: 0.0,
                    c: 0.01,
                    d: 0.0,
                },
                20.0,
            )
        };
        let mut prev = c.eval(0.0).0;
        let mut len = 0.0;
        for i in 1..=2000 {
            let q = c.eval(20.0 * i as f64 / 2000.0).0;
            len += (q - prev).length();
            prev = q;
        }
        assert!((len - 20.0).abs() < 1e-3, "{len}");
    }
}
