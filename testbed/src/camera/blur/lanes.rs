//! The blur's geometry four pixels at a time on AVX2 vectors.

use std::ops::{Add, Div, Mul, Sub};

use pulp::x86::V3;
use pulp::{cast, f64x4};

use super::{Arith, Exposure, Path};

/// Pixels blurred side by side.
pub(super) const LANES: usize = 4;

/// Four floats on a vector, with the instructions to work on them.
#[derive(Clone, Copy)]
struct Four {
    simd: V3,
    v: f64x4,
}

/// `Four`'s operator `$op` (`$method`) as the vector instruction `$simd`.
macro_rules! lanewise {
    ($op:ident, $method:ident, $simd:ident) => {
        impl $op for Four {
            type Output = Self;
            #[inline(always)]
            fn $method(self, o: Self) -> Self {
                Self {
                    simd: self.simd,
                    v: self.simd.$simd(self.v, o.v),
                }
            }
        }
    };
}

lanewise!(Add, add, add_f64x4);
lanewise!(Sub, sub, sub_f64x4);
lanewise!(Mul, mul, mul_f64x4);
lanewise!(Div, div, div_f64x4);

impl Arith for Four {
    #[inline(always)]
    fn splat(&self, x: f64) -> Self {
        Self {
            simd: self.simd,
            v: self.simd.splat_f64x4(x),
        }
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        Self {
            simd: self.simd,
            v: self.simd.sqrt_f64x4(self.v),
        }
    }
}

/// The paths of the pixels `u..u + 4` of row `v`, computed together; `y`
/// is the row's [`Exposure::ray_y`].
#[inline(always)]
pub(super) fn paths(simd: V3, e: &Exposure<'_>, [u, v]: [usize; 2], y: f64) -> [Path<f64>; LANES] {
    let four = |x: [f64; LANES]| Four { simd, v: cast(x) };
    let x: [f64; LANES] = std::array::from_fn(|l| e.ray_x[u + l]);
    let depth: [f64; LANES] = std::array::from_fn(|l| e.depth(u + l, v));
    let path = e.path(four(x), four([y; LANES]), four(depth));
    let lanes = |f: Four| -> [f64; LANES] { cast(f.v) };
    let (u0, v0, u1, v1) = (
        lanes(path.u0),
        lanes(path.v0),
        lanes(path.u1),
        lanes(path.v1),
    );
    let (length, z0, z1) = (lanes(path.length), lanes(path.z0), lanes(path.z1));
    std::array::from_fn(|l| Path {
        u0: u0[l],
        v0: v0[l],
        u1: u1[l],
        v1: v1[l],
        length: length[l],
        z0: z0[l],
        z1: z1[l],
    })
}

/// One row of the blur.
pub(super) struct Row<'a, 'b> {
    pub(super) simd: V3,
    pub(super) exposure: &'a Exposure<'b>,
    pub(super) v: usize,
    pub(super) row: &'a mut [f32],
}

impl pulp::NullaryFnOnce for Row<'_, '_> {
    type Output = ();

    #[inline(always)]
    fn call(self) {
        let Self {
            simd,
            exposure: e,
            v,
            row,
        } = self;
        let y = e.ray_y(v);
        let whole = row.len() / LANES * LANES;
        let (head, tail) = row.split_at_mut(whole);
        for (chunk, out) in head.chunks_exact_mut(LANES).enumerate() {
            let u = chunk * LANES;
            for (l, (out, path)) in out.iter_mut().zip(paths(simd, e, [u, v], y)).enumerate() {
                *out = e.integrate(u + l, v, &path);
            }
        }
        e.blur_pixels(v, whole, tail);
    }
}
