//! Brown–Conrady lens distortion in OpenCV's convention (`cv2.projectPoints` with `D = [k1, k2, p1, p2, k3]`),
//! on normalised image coordinates `(x, y) = (X/Z, Y/Z)`: the forward map ([`Lens::distort`], closed form) and
//! its inverse ([`Lens::undistort`], Newton's method).
//!
//! The polynomial folds back far from the centre (with `k1 < 0` a point far outside the image would land
//! inside it). [`Lens::new`] finds the radius up to which the radial map grows; beyond it the lens scales
//! points radially by its factor at that radius, so every point outside the valid disc stays outside it.

/// Normalised radius up to which a lens is searched for its fold (about 84° off axis).
const MAX_RADIUS: f64 = 10.0;

/// A Brown–Conrady lens.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lens {
    /// `[k1, k2, p1, p2, k3]`.
    pub coefficients: [f64; 5],
    /// Squared normalised radius up to which the radial map `r ↦ r (1 + k1 r² + k2 r⁴ + k3 r⁶)` grows.
    pub valid_r2: f64,
}

impl Lens {
    /// The lens of OpenCV's coefficients `[k1, k2, p1, p2, k3]`.
    pub fn new(coefficients: [f64; 5]) -> Lens {
        let [k1, k2, _, _, k3] = coefficients;
        // d/dr [r s(r)] = 1 + 3 k1 r² + 5 k2 r⁴ + 7 k3 r⁶: the first radius where it reaches zero (stepped
        // finely enough for any lens the spec accepts, then bisected).
        let slope = |r: f64| {
            let r2 = r * r;
            1.0 + r2 * (3.0 * k1 + r2 * (5.0 * k2 + r2 * 7.0 * k3))
        };
        let mut valid = MAX_RADIUS;
        let step = 1.0 / 1024.0;
        let mut r = step;
        while r <= MAX_RADIUS {
            let s = slope(r);
            if s.is_nan() || s <= 0.0 {
                let (mut lo, mut hi) = (r - step, r);
                for _ in 0..40 {
                    let mid = 0.5 * (lo + hi);
                    if slope(mid) > 0.0 { lo = mid } else { hi = mid }
                }
                valid = lo;
                break;
            }
            r += step;
        }
        Lens {
            coefficients,
            valid_r2: valid * valid,
        }
    }

    /// Whether every coefficient is zero (a pinhole).
    pub fn is_pinhole(&self) -> bool {
        self.coefficients == [0.0; 5]
    }

    /// The polynomial itself, without the radial extension.
    fn polynomial(&self, x: f64, y: f64) -> (f64, f64) {
        let [k1, k2, p1, p2, k3] = self.coefficients;
        let r2 = x * x + y * y;
        let s = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3));
        (
            x * s + 2.0 * p1 * x * y + p2 * (r2 + 2.0 * x * x),
            y * s + p1 * (r2 + 2.0 * y * y) + 2.0 * p2 * x * y,
        )
    }

    /// Where the lens shows the normalised point `(x, y)`.
    pub fn distort(&self, x: f64, y: f64) -> (f64, f64) {
        let r2 = x * x + y * y;
        if r2 <= self.valid_r2 {
            return self.polynomial(x, y);
        }
        // Beyond the fold: the point on the valid circle in the same direction, scaled out again.
        let k = (r2 / self.valid_r2).sqrt();
        let (xd, yd) = self.polynomial(x / k, y / k);
        (xd * k, yd * k)
    }

    /// The normalised point the lens shows at `(xd, yd)` (the inverse of [`Lens::distort`] inside the valid
    /// disc): Newton's method on the polynomial from `(xd, yd)`; `None` when it does not converge to 1e-12.
    pub fn undistort(&self, xd: f64, yd: f64) -> Option<(f64, f64)> {
        let [k1, k2, p1, p2, k3] = self.coefficients;
        let (mut x, mut y) = (xd, yd);
        for _ in 0..50 {
            let (fx, fy) = self.polynomial(x, y);
            let (ex, ey) = (fx - xd, fy - yd);
            if ex * ex + ey * ey < 1e-24 {
                return (x * x + y * y <= self.valid_r2).then_some((x, y));
            }
            let r2 = x * x + y * y;
            let s = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3));
            // ds/dr² ; ∂s/∂x = 2x·ds/dr².
            let ds = k1 + r2 * (2.0 * k2 + r2 * 3.0 * k3);
            let (sx, sy) = (2.0 * x * ds, 2.0 * y * ds);
            let a = s + x * sx + 2.0 * p1 * y + 6.0 * p2 * x;
            let b = x * sy + 2.0 * p1 * x + 2.0 * p2 * y;
            let c = y * sx + 2.0 * p1 * x + 2.0 * p2 * y;
            let d = s + y * sy + 6.0 * p1 * y + 2.0 * p2 * x;
            let det = a * d - b * c;
            if !det.is_finite() || det.abs() < 1e-12 {
                return None;
            }
            x -= (d * ex - b * ey) / det;
            y -= (a * ey - c * ex) / det;
        }
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_pinhole_changes_nothing() {
        let lens = Lens::new([0.0; 5]);
        assert!(lens.is_pinhole());
        assert_eq!(lens.distort(0.3, -0.7), (0.3, -0.7));
        assert_eq!(lens.undistort(0.3, -0.7), Some((0.3, -0.7)));
    }

    #[test]
    fn distortion_follows_opencv_and_undistortion_inverts_it() {
        // cv2.projectPoints(np.array([[0.5, -0.25, 1.0]]), zeros, zeros, eye(3), D) with D below gives
        // x' = 0.5·(1 − 0.3·0.3125 + 0.1·0.09765625 − 0.01·0.030517578125) + 2·0.001·0.5·(−0.25)
        //      + 0.002·(0.3125 + 0.5) — the formula is checked term by term here.
        let d = [-0.3, 0.1, 0.001, 0.002, -0.01];
        let lens = Lens::new(d);
        let (x, y) = (0.5, -0.25);
        let r2: f64 = 0.3125;
        let s = 1.0 - 0.3 * r2 + 0.1 * r2 * r2 - 0.01 * r2 * r2 * r2;
        let want = (
            x * s + 2.0 * 0.001 * x * y + 0.002 * (r2 + 2.0 * x * x),
            y * s + 0.001 * (r2 + 2.0 * y * y) + 2.0 * 0.002 * x * y,
        );
        let got = lens.distort(x, y);
        assert!((got.0 - want.0).abs() < 1e-15 && (got.1 - want.1).abs() < 1e-15);
        for i in -10..=10 {
            for j in -6..=6 {
                let (x, y) = (f64::from(i) * 0.09, f64::from(j) * 0.09);
                let (xd, yd) = lens.distort(x, y);
                let (xu, yu) = lens.undistort(xd, yd).expect("converges inside the valid disc");
                assert!((xu - x).abs() < 1e-10 && (yu - y).abs() < 1e-10, "({x}, {y})");
            }
        }
    }

    #[test]
    fn the_fold_is_found_and_points_beyond_it_stay_outside() {
        // r (1 − 0.3 r²) grows up to r = 1/√0.9.
        let lens = Lens::new([-0.3, 0.0, 0.0, 0.0, 0.0]);
        assert!(
            (lens.valid_r2.sqrt() - 1.0 / 0.9f64.sqrt()).abs() < 1e-6,
            "{}",
            lens.valid_r2
        );
        let edge = lens.distort(lens.valid_r2.sqrt(), 0.0).0;
        let mut last = 0.0;
        for k in 1..400 {
            let r = f64::from(k) * 0.01;
            let rd = lens.distort(r, 0.0).0;
            assert!(rd > last, "radial map grows at r = {r}");
            last = rd;
        }
        assert!(lens.distort(3.0, 0.0).0 > edge);
        // A lens that never folds.
        assert_eq!(Lens::new([0.1, 0.0, 0.0, 0.0, 0.0]).valid_r2, MAX_RADIUS * MAX_RADIUS);
    }
}
