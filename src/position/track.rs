//! Forward-mode derivatives of the quantities a joint residual is built from: a vector or a
//! scalar together with its derivative with respect to the twists of the joint's two bodies,
//! `(ω_A, v_A, ω_B, v_B)` (12 columns, spatial form; planar and spherical twists are embedded
//! in it by [`super::pose::embed_columns`]).

use nalgebra::{Matrix3, RowSVector, SMatrix, Vector3};

/// Derivative columns: the first body's twist (6), then the second body's (6).
pub(crate) const NC: usize = 12;

/// A world vector and its derivative.
#[derive(Clone, Copy, Debug)]
pub(crate) struct TV {
    pub v: Vector3<f64>,
    pub d: SMatrix<f64, 3, NC>,
}

/// A scalar and its derivative.
#[derive(Clone, Copy, Debug)]
pub(crate) struct TS {
    pub v: f64,
    pub d: RowSVector<f64, NC>,
}

fn skew(a: &Vector3<f64>) -> Matrix3<f64> {
    Matrix3::new(0.0, -a.z, a.y, a.z, 0.0, -a.x, -a.y, a.x, 0.0)
}

impl TV {
    /// A point of body `side` (0 first, 1 second) now at world position `y`: `dy = ω × y + v`.
    pub fn point(y: Vector3<f64>, side: usize) -> TV {
        let mut d = SMatrix::<f64, 3, NC>::zeros();
        let c = 6 * side;
        d.fixed_view_mut::<3, 3>(0, c).copy_from(&(-skew(&y)));
        d.fixed_view_mut::<3, 3>(0, c + 3)
            .copy_from(&Matrix3::identity());
        TV { v: y, d }
    }

    /// A direction of body `side` now along `u`: `du = ω × u`.
    pub fn dir(u: Vector3<f64>, side: usize) -> TV {
        let mut d = SMatrix::<f64, 3, NC>::zeros();
        d.fixed_view_mut::<3, 3>(0, 6 * side)
            .copy_from(&(-skew(&u)));
        TV { v: u, d }
    }

    pub fn sub(&self, o: &TV) -> TV {
        TV {
            v: self.v - o.v,
            d: self.d - o.d,
        }
    }

    pub fn dot(&self, o: &TV) -> TS {
        TS {
            v: self.v.dot(&o.v),
            d: o.v.transpose() * self.d + self.v.transpose() * o.d,
        }
    }

    pub fn norm(&self) -> TS {
        let n = self.v.norm().max(1e-300);
        TS {
            v: n,
            d: (self.v.transpose() * self.d) / n,
        }
    }
}

impl TS {
    pub fn constant(v: f64) -> TS {
        TS {
            v,
            d: RowSVector::zeros(),
        }
    }

    pub fn sub(&self, o: &TS) -> TS {
        TS {
            v: self.v - o.v,
            d: self.d - o.d,
        }
    }

    pub fn scale(&self, s: f64) -> TS {
        TS {
            v: self.v * s,
            d: self.d * s,
        }
    }

    /// `atan2(self, x)`.
    pub fn atan2(&self, x: &TS) -> TS {
        let r2 = (self.v * self.v + x.v * x.v).max(1e-300);
        TS {
            v: self.v.atan2(x.v),
            d: (self.d * x.v - x.d * self.v) / r2,
        }
    }
}
