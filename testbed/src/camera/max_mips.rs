//! Rays cast over the ground's height map through its maximum mipmap
//! (Tevs, Ihrke & Seidel, "Maximum mipmaps for fast, accurate, and
//! scalable dynamic height field rendering", I3D 2008): level 0 holds the
//! highest corner of each map cell, level `k` the highest of the `2^k ×
//! 2^k` cells under it. A ray passes over a whole block in one step when it
//! stays above the block's highest point, descends into the block
//! otherwise, and in a single cell meets the bilinear surface exactly (a
//! quadratic along the ray). The hit is the ray's first intersection with
//! the same surface that [`super::GroundMaps::height`] interpolates.

use rayon::prelude::*;

mod packet;
pub(super) use packet::RayQuery;

use super::convert::{as_f64, truncate};
use super::tiled::TiledGrid;

/// The level a ray starts at (blocks of 64 cells, 16 cm on the testbed's
/// 2.5 mm map): the hit is the same from any level; from this one the
/// rendered testbed's rays take fewer instructions than from levels 2, 4
/// or 8 (4 % fewer than from level 4, 13 % fewer than from level 2).
const START_LEVEL: usize = 6;

/// The maximum mipmap of a square height map of `n × n` samples.
pub(super) struct MaxMips {
    /// Level `k ≥ 1` at index `k − 1`: the highest height of each block of
    /// `2^k × 2^k` cells. Level 0, the highest corner of each cell, is not
    /// stored: a ray reads it from the cell's four corners, which it needs
    /// anyway to meet the cell's surface, so the largest level costs no
    /// memory and no cache misses of its own (storing it makes the
    /// rendered testbed's rays 13 % slower).
    levels: Vec<TiledGrid>,
    /// Blocks per side of each level, from level 0.
    sides: Vec<usize>,
}

/// A ray in map units: the horizontal position in cells, the height in
/// metres, both affine in the ray's length `t` (m).
#[derive(Clone, Copy)]
struct MapRay {
    u0: f64,
    v0: f64,
    z0: f64,
    du: f64,
    dv: f64,
    dz: f64,
    /// `1 / du` and `1 / dv` (infinite along an axis the ray keeps).
    inv_du: f64,
    inv_dv: f64,
}

impl MapRay {
    /// The ray from `origin` along `dir` (metres, the map's origin at
    /// `(0, 0)`) over a map of `cell_m` per cell.
    fn new(origin: [f64; 3], dir: [f64; 3], cell_m: f64) -> Self {
        Self {
            u0: origin[0] / cell_m,
            v0: origin[1] / cell_m,
            z0: origin[2],
            du: dir[0] / cell_m,
            dv: dir[1] / cell_m,
            dz: dir[2],
            inv_du: cell_m / dir[0],
            inv_dv: cell_m / dir[1],
        }
    }

    fn z(&self, t: f64) -> f64 {
        self.z0 + self.dz * t
    }

    /// The ray's lowest height over `[t, exit]` (`t ≤ exit`): at the end
    /// it descends towards, the other's rounding never being lower (both
    /// roundings are monotone), so this is `z(t).min(z(exit))`.
    #[inline(always)]
    fn lowest(&self, t: f64, exit: f64) -> f64 {
        if self.dz < 0.0 {
            self.z(exit)
        } else {
            self.z(t)
        }
    }

    /// Where the ray leaves the block `(i, j)` of `level`, and which of
    /// its two axes it leaves by (`(true, false)` across u, both at a
    /// corner). The boundary `k · 2^level` is the integer `k << level`
    /// converted, the same float as `k` times the block's size.
    #[inline(always)]
    fn exit(&self, i: usize, j: usize, level: usize) -> (f64, bool, bool) {
        let across = |o: f64, d: f64, inv: f64, k: usize| {
            if d > 0.0 {
                (as_f64((k + 1) << level) - o) * inv
            } else if d < 0.0 {
                (as_f64(k << level) - o) * inv
            } else {
                f64::INFINITY
            }
        };
        let (tu, tv) = (
            across(self.u0, self.du, self.inv_du, i),
            across(self.v0, self.dv, self.inv_dv, j),
        );
        (tu.min(tv), tu <= tv, tv <= tu)
    }
}

/// A ray's walk over the mipmap: the ray, the span left to walk, and the
/// block (`level`, `i`, `j`) it is in.
struct Walk {
    ray: MapRay,
    t: f64,
    t_end: f64,
    level: usize,
    i: usize,
    j: usize,
}

/// The side of a block of `level` in cells, `2^level`, exactly.
#[inline(always)]
fn block_size(level: usize) -> f64 {
    f64::from(1u32 << level)
}

/// `1 / size` for a power of two `size ≥ 1`: the power of two with the
/// opposite exponent, made from its bits (exact, and no division).
#[inline(always)]
fn power_of_two_recip(size: f64) -> f64 {
    f64::from_bits(((2 * 1023u64) << 52).wrapping_sub(size.to_bits()))
}

/// The block along one axis that holds the coordinate `c ≥ 0` (cells) for
/// a ray moving by `d` per metre: a coordinate on a boundary belongs to the
/// block the ray is entering. (Truncation is the floor of a non-negative
/// number, and cheaper than `floor` where the CPU has no rounding
/// instruction.)
fn block(c: f64, d: f64, size: f64, side: usize) -> usize {
    let q = (c * power_of_two_recip(size)).max(0.0);
    let k = truncate(q);
    let k = if d < 0.0 && as_f64(k) == q {
        k.saturating_sub(1)
    } else {
        k
    };
    k.min(side - 1)
}

/// Of the two children `2k` and `2k + 1` (at `level`, the last being
/// `last`) of the block `k` along one axis, the one that holds the
/// coordinate `c`: the upper past their common boundary, or on it when the
/// ray does not move down the axis. This is [`block`] at `level` clamped
/// to the two children (the boundary `(2k + 1) · 2^level` is exact, so
/// comparing `c` with it is comparing `c / 2^level` with `2k + 1`).
#[inline(always)]
fn child(c: f64, d: f64, k: usize, level: usize, last: usize) -> usize {
    let boundary = as_f64((2 * k + 1) << level);
    let upper = c > boundary || (c == boundary && d >= 0.0);
    (2 * k + usize::from(upper)).min(last)
}

/// One step to the next block along an axis; `None` past the map's edge.
#[inline(always)]
fn step(k: usize, d: f64, side: usize) -> Option<usize> {
    if d > 0.0 {
        (k + 1 < side).then_some(k + 1)
    } else {
        k.checked_sub(1)
    }
}

impl MaxMips {
    /// The mipmap of `height` (at least 2 × 2 samples).
    pub(super) fn build(height: &TiledGrid) -> Self {
        let cells = height.side() - 1;
        let base: Vec<f32> = (0..cells)
            .into_par_iter()
            .flat_map_iter(|j| {
                (0..cells).map(move |i| {
                    let at = |i: usize, j: usize| height.at(i, j);
                    at(i, j)
                        .max(at(i + 1, j))
                        .max(at(i, j + 1).max(at(i + 1, j + 1)))
                })
            })
            .collect();
        let mut levels = Vec::new();
        let mut sides = vec![cells];
        let mut below = base;
        while let Some(&side) = sides.last() {
            if side <= 1 {
                break;
            }
            let up = side.div_ceil(2);
            let next: Vec<f32> = (0..up)
                .into_par_iter()
                .flat_map_iter(|j| {
                    let below = &below;
                    (0..up).map(move |i| {
                        let mut m = f32::NEG_INFINITY;
                        for jj in (2 * j)..(2 * j + 2).min(side) {
                            for ii in (2 * i)..(2 * i + 2).min(side) {
                                m = m.max(below[jj * side + ii]);
                            }
                        }
                        m
                    })
                })
                .collect();
            levels.push(TiledGrid::from_row_major(up, &next));
            sides.push(up);
            below = next;
        }
        Self { levels, sides }
    }

    /// The first length `t` in `[t_start, t_end]` at which the ray from
    /// `origin` along `dir` (both in metres, the map's origin at `(0, 0)`,
    /// `cell_m` per cell) meets the bilinear surface of `height`, or
    /// `None` if it stays above it (or outside the map) over that span.
    pub(super) fn first_hit(
        &self,
        height: &TiledGrid,
        cell_m: f64,
        origin: [f64; 3],
        dir: [f64; 3],
        t_start: f64,
        t_end: f64,
    ) -> Option<f64> {
        self.first_hit_from(START_LEVEL, height, cell_m, origin, dir, [t_start, t_end])
    }

    /// Where the walk of the ray from `origin` along `dir` over `[t_start,
    /// t_end]` starts at level `start` (or the top, if lower): the ray's
    /// span over the map and the block there, or `None` if the ray misses
    /// the map over that span.
    fn walk(
        &self,
        start: usize,
        cell_m: f64,
        origin: [f64; 3],
        dir: [f64; 3],
        [t_start, t_end]: [f64; 2],
    ) -> Option<Walk> {
        let ray = MapRay::new(origin, dir, cell_m);
        let cells = self.sides[0];
        // The span of the ray over the map.
        let (mut t, mut t_end) = (t_start, t_end);
        for (o, d) in [(ray.u0, ray.du), (ray.v0, ray.dv)] {
            if d == 0.0 {
                if !(0.0..=cells as f64).contains(&o) {
                    return None;
                }
                continue;
            }
            let (a, b) = (-o / d, (cells as f64 - o) / d);
            t = t.max(a.min(b));
            t_end = t_end.min(a.max(b));
        }
        if t > t_end {
            return None;
        }
        let level = (self.sides.len() - 1).min(start);
        let side = self.sides[level];
        Some(Walk {
            ray,
            t,
            t_end,
            level,
            i: block(ray.u0 + ray.du * t, ray.du, block_size(level), side),
            j: block(ray.v0 + ray.dv * t, ray.dv, block_size(level), side),
        })
    }

    /// [`Self::first_hit`] starting at level `start` (or the top, if
    /// lower).
    fn first_hit_from(
        &self,
        start: usize,
        height: &TiledGrid,
        cell_m: f64,
        origin: [f64; 3],
        dir: [f64; 3],
        [t_start, t_end]: [f64; 2],
    ) -> Option<f64> {
        let Walk {
            ray,
            mut t,
            t_end,
            mut level,
            mut i,
            mut j,
        } = self.walk(start, cell_m, origin, dir, [t_start, t_end])?;
        let top = self.sides.len() - 1;
        loop {
            let side = self.sides[level];
            let (exit, across_u, across_v) = ray.exit(i, j, level);
            // `exit.clamp(t, t_end)`, `t ≤ t_end` holding throughout.
            let exit = if exit < t {
                t
            } else if exit > t_end {
                t_end
            } else {
                exit
            };
            let corners = (level == 0).then(|| Corners::of(height, i, j));
            let highest = f64::from(match &corners {
                Some(c) => c.highest(),
                None => self.levels[level - 1].at(i, j),
            });
            let below = ray.lowest(t, exit) <= highest;
            if level > 0 && below {
                // The ray may meet the ground in this block: look closer.
                level -= 1;
                let last = self.sides[level] - 1;
                i = child(ray.u0 + ray.du * t, ray.du, i, level, last);
                j = child(ray.v0 + ray.dv * t, ray.dv, j, level, last);
                continue;
            }
            if let Some(c) = &corners
                && below
                && let Some(hit) = cell_hit(c, &ray, i, j, t, exit)
            {
                return Some(hit);
            }
            // Over this block: on to the next one.
            if exit >= t_end {
                return None;
            }
            t = exit;
            let mut parent_crossed = false;
            // Past the map's edge: nothing more to meet.
            if across_u {
                let next = step(i, ray.du, side)?;
                parent_crossed |= next >> 1 != i >> 1;
                i = next;
            }
            if across_v {
                let next = step(j, ray.dv, side)?;
                parent_crossed |= next >> 1 != j >> 1;
                j = next;
            }
            if parent_crossed && level < top {
                level += 1;
                i /= 2;
                j /= 2;
            }
        }
    }
}

/// The heights at the four corners of a map cell.
struct Corners {
    h00: f32,
    h10: f32,
    h01: f32,
    h11: f32,
}

impl Corners {
    /// The corners of the cell `(i, j)` of `height`.
    #[inline(always)]
    fn of(height: &TiledGrid, i: usize, j: usize) -> Self {
        Self {
            h00: height.at(i, j),
            h10: height.at(i + 1, j),
            h01: height.at(i, j + 1),
            h11: height.at(i + 1, j + 1),
        }
    }

    /// The highest corner: level 0 of the mipmap, the same value (a
    /// maximum of floats is exact in any order).
    fn highest(&self) -> f32 {
        self.h00.max(self.h10).max(self.h01.max(self.h11))
    }
}

/// The first `t` in `[t_in, t_out]` at which the ray meets the bilinear
/// patch of the map cell `(i, j)` with `corners`: along the ray the
/// patch's height is a quadratic in `t`, so the gap `z − h` is one too.
fn cell_hit(
    corners: &Corners,
    ray: &MapRay,
    i: usize,
    j: usize,
    t_in: f64,
    t_out: f64,
) -> Option<f64> {
    let [h00, h10, h01, h11] = [corners.h00, corners.h10, corners.h01, corners.h11].map(f64::from);
    let (a, b) = (h10 - h00, h01 - h00);
    let c = h11 - h10 - h01 + h00;
    let s0 = ray.u0 + ray.du * t_in - as_f64(i);
    let r0 = ray.v0 + ray.dv * t_in - as_f64(j);
    // gap(τ) = g0 + g1 τ + g2 τ², τ = t − t_in.
    let g0 = ray.z(t_in) - (h00 + a * s0 + b * r0 + c * s0 * r0);
    let g1 = ray.dz - a * ray.du - b * ray.dv - c * (s0 * ray.dv + r0 * ray.du);
    let g2 = -c * ray.du * ray.dv;
    if g0 <= 0.0 {
        return Some(t_in);
    }
    let span = t_out - t_in;
    let tau = smallest_root(g0, g1, g2)?;
    (tau <= span).then_some(t_in + tau)
}

/// The smallest positive root of `g0 + g1 τ + g2 τ²` with `g0 > 0`, where
/// the polynomial first turns non-positive.
fn smallest_root(g0: f64, g1: f64, g2: f64) -> Option<f64> {
    if g2.abs() <= 1e-12 * (g1.abs() + g0.abs()) {
        return (g1 < 0.0).then(|| -g0 / g1);
    }
    let disc = g1 * g1 - 4.0 * g2 * g0;
    if disc < 0.0 {
        return None;
    }
    // The stable pair of roots: q = −(g1 + sign(g1) √disc) / 2.
    let q = -0.5 * (g1 + g1.signum() * disc.sqrt());
    let (r1, r2) = (q / g2, if q != 0.0 { g0 / q } else { f64::INFINITY });
    [r1, r2]
        .into_iter()
        .filter(|r| *r > 0.0 && r.is_finite())
        .min_by(f64::total_cmp)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_smallest_root_is_the_first_crossing() {
        // (τ − 1)(τ − 3) = 3 − 4τ + τ².
        assert!((smallest_root(3.0, -4.0, 1.0).unwrap() - 1.0).abs() < 1e-12);
        // Linear: 2 − τ.
        assert!((smallest_root(2.0, -1.0, 0.0).unwrap() - 2.0).abs() < 1e-12);
        // Always positive: 1 + τ².
        assert!(smallest_root(1.0, 0.0, 1.0).is_none());
        // Opening downward: 1 + τ − τ² crosses at (1 + √5) / 2.
        let r = smallest_root(1.0, 1.0, -1.0).unwrap();
        assert!((r - 0.5 * (1.0 + 5f64.sqrt())).abs() < 1e-12);
    }

    /// The first hit by brute force: every cell's span along the ray
    /// (slabs), its patch met by the same quadratic, the earliest kept.
    fn brute_force_hit(
        height: &TiledGrid,
        cell_m: f64,
        origin: [f64; 3],
        dir: [f64; 3],
        span: [f64; 2],
    ) -> Option<f64> {
        let cells = height.side() - 1;
        let ray = MapRay::new(origin, dir, cell_m);
        let slab = |o: f64, d: f64, k: usize| -> (f64, f64) {
            let (a, b) = ((k as f64 - o) / d, ((k + 1) as f64 - o) / d);
            (a.min(b), a.max(b))
        };
        let mut best: Option<f64> = None;
        for j in 0..cells {
            for i in 0..cells {
                let ((a0, a1), (b0, b1)) = (slab(ray.u0, ray.du, i), slab(ray.v0, ray.dv, j));
                let (t_in, t_out) = (a0.max(b0).max(span[0]), a1.min(b1).min(span[1]));
                if t_in > t_out {
                    continue;
                }
                if let Some(t) = cell_hit(&Corners::of(height, i, j), &ray, i, j, t_in, t_out) {
                    best = Some(best.map_or(t, |b: f64| b.min(t)));
                }
            }
        }
        best
    }

    #[test]
    fn the_first_hit_is_the_brute_force_one_from_every_start_level() {
        // A rough 33 × 33 map (32 cells a side, 6 levels) of 1 cm cells.
        let n = 33;
        let mut state = 7u64;
        let mut uniform = move || {
            state = state
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        let values: Vec<f32> = (0..n * n)
            .map(|k| {
                let (x, y) = ((k % n) as f64, (k / n) as f64);
                (0.03 * (0.3 * x).sin() * (0.2 * y).cos() + 0.01 * uniform()) as f32
            })
            .collect();
        let height = TiledGrid::from_row_major(n, &values);
        let mips = MaxMips::build(&height);
        let cell_m = 0.01;
        let (mut hits, mut misses) = (0, 0);
        for _ in 0..400 {
            let origin = [0.32 * uniform(), 0.32 * uniform(), 0.02 + 0.1 * uniform()];
            let (azimuth, down) = (std::f64::consts::TAU * uniform(), 0.02 + 0.6 * uniform());
            let dir = [
                down.cos() * azimuth.cos(),
                down.cos() * azimuth.sin(),
                -down.sin(),
            ];
            let span = [0.0, 1.0];
            let expected = brute_force_hit(&height, cell_m, origin, dir, span);
            let from = |start| mips.first_hit_from(start, &height, cell_m, origin, dir, span);
            let found = from(START_LEVEL);
            match (found, expected) {
                (Some(a), Some(b)) => {
                    assert!((a - b).abs() <= 1e-9, "{a} against {b}");
                    hits += 1;
                }
                (None, None) => misses += 1,
                other => panic!("{other:?} for the ray from {origin:?} along {dir:?}"),
            }
            for start in 0..8 {
                assert_eq!(from(start), found, "from level {start}");
            }
        }
        assert!(hits > 100 && misses > 20, "{hits} hits, {misses} misses");
    }

    #[test]
    fn a_power_of_twos_reciprocal_from_its_bits_is_the_division() {
        for level in 0..40 {
            let size = f64::from_bits((1023 + level) << 52);
            assert_eq!(size, 2f64.powi(level as i32));
            assert_eq!(power_of_two_recip(size).to_bits(), size.recip().to_bits());
        }
    }

    #[test]
    fn a_child_is_the_block_clamped_to_the_two_children() {
        // On and around every boundary, for both directions and none, at
        // levels 0 to 3, odd sides (a last block with one child) included.
        for level in 0..4 {
            let half = block_size(level);
            for side in [5usize, 6, 9] {
                for k in 0..side.div_ceil(2) {
                    let last = side - 1;
                    for offset in [-1.5, -1e-9, 0.0, 1e-9, 0.5, 1.0, 2.0, 2.5] {
                        let c = (as_f64(2 * k + 1) + offset) * half;
                        for d in [-1.0, 0.0, 1.0] {
                            let expected =
                                block(c, d, half, side).clamp(2 * k, (2 * k + 1).min(last));
                            assert_eq!(child(c, d, k, level, last), expected, "{c} {d} {k}");
                        }
                    }
                    assert_eq!(child(f64::NAN, 1.0, k, level, last), 2 * k);
                }
            }
        }
    }

    #[test]
    fn every_level_bounds_the_level_below() {
        let n = 11;
        let height: Vec<f32> = (0..n * n).map(|k| ((k * 37) % 17) as f32 * 0.01).collect();
        let mips = MaxMips::build(&TiledGrid::from_row_major(n, &height));
        assert_eq!(mips.sides, vec![10, 5, 3, 2, 1]);
        let top = mips.levels.last().unwrap().at(0, 0);
        assert_eq!(top, height.iter().copied().fold(f32::MIN, f32::max));
    }
}
