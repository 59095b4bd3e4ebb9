//! One lock step of a packet's four walks on AVX2 vectors: the block's
//! highest point looked up per lane, every decision of the single-ray walk
//! ([`MaxMips::first_hit`]) made as a select, and the integers (levels,
//! block indices) on 64-bit lanes, turned into floats exactly.

use pulp::x86::V3;
use pulp::{cast, f64x4, i64x4, m64x4, u64x4};

use super::{LANES, Rays, Walks, signed};
use crate::camera::max_mips::{Corners, MaxMips, cell_hit};
use crate::camera::tiled::TiledGrid;

/// Blocks per side of `level` over `cells` cells a side: `⌈cells /
/// 2^level⌉` (each level halves the one below, rounding up).
#[inline(always)]
fn blocks(s: V3, cells: i64x4, level: i64x4) -> i64x4 {
    let one = s.splat_i64x4(1);
    let size = shl(s, one, level);
    let round_up = s.wrapping_sub_i64x4(s.wrapping_add_i64x4(cells, size), one);
    cast(s.shr_dyn_u64x4(cast(round_up), cast(level)))
}

/// The place of the blocks `(i, j)` in the tiles of a level of `side`
/// blocks a side ([`TiledGrid::index_of`]; every value below 2³²).
#[inline(always)]
fn tiled_index(s: V3, side: i64x4, i: i64x4, j: i64x4) -> i64x4 {
    let seven = s.splat_u64x4(7);
    let (i, j, side): (u64x4, u64x4, u64x4) = (cast(i), cast(j), cast(side));
    let tiles = s.shr_const_u64x4::<3>(s.wrapping_add_u64x4(side, seven));
    let row_of_tiles: u64x4 = cast(
        s.avx2
            ._mm256_mul_epu32(cast(s.shr_const_u64x4::<3>(j)), cast(tiles)),
    );
    let tile = s.wrapping_add_u64x4(row_of_tiles, s.shr_const_u64x4::<3>(i));
    let within = s.wrapping_add_u64x4(
        s.shl_const_u64x4::<3>(s.and_u64x4(j, seven)),
        s.and_u64x4(i, seven),
    );
    cast(s.wrapping_add_u64x4(s.shl_const_u64x4::<6>(tile), within))
}

/// An integer in `[0, 2⁵²)` as a float, exactly: its bits under the
/// exponent of 2⁵², less 2⁵².
#[inline(always)]
fn to_f64(simd: V3, k: i64x4) -> f64x4 {
    const TWO_52: f64 = 4_503_599_627_370_496.0;
    let bits = simd.or_u64x4(cast(k), simd.splat_u64x4(TWO_52.to_bits()));
    simd.sub_f64x4(cast(bits), simd.splat_f64x4(TWO_52))
}

/// `a << amount` per lane (`amount` in `[0, 63]`).
#[inline(always)]
fn shl(simd: V3, a: i64x4, amount: i64x4) -> i64x4 {
    cast(simd.shl_dyn_u64x4(cast::<i64x4, u64x4>(a), cast(amount)))
}

/// The length at which each ray crosses its block's exit boundary
/// along one axis (`MapRay::exit`'s `across`): `k` the block index,
/// `upper` 1 where the ray moves up the axis, infinite where the ray
/// keeps the axis (`fixed`).
#[inline(always)]
fn across(
    s: V3,
    k: i64x4,
    level: i64x4,
    upper: i64x4,
    o: f64x4,
    inv: f64x4,
    fixed: m64x4,
) -> f64x4 {
    let boundary = to_f64(s, shl(s, s.wrapping_add_i64x4(k, upper), level));
    let t = s.mul_f64x4(s.sub_f64x4(boundary, o), inv);
    s.select_f64x4(fixed, s.splat_f64x4(f64::INFINITY), t)
}

/// `child` per lane: of the children `2k` and `2k + 1` at `level` of
/// the block `k`, the one holding the coordinate `c`, clamped to
/// `last`; `rising` where the ray moves up the axis or keeps it.
#[inline(always)]
fn child(s: V3, c: f64x4, rising: m64x4, k: i64x4, level: i64x4, last: i64x4) -> i64x4 {
    let one = s.splat_i64x4(1);
    let twice = s.wrapping_add_i64x4(k, k);
    let odd = s.wrapping_add_i64x4(twice, one);
    let boundary = to_f64(s, shl(s, odd, level));
    let upper = s.or_m64x4(
        s.cmp_gt_f64x4(c, boundary),
        s.and_m64x4(s.cmp_eq_f64x4(c, boundary), rising),
    );
    let k = s.select_i64x4(upper, odd, twice);
    s.select_i64x4(s.cmp_gt_i64x4(k, last), last, k)
}

/// Where a block index is off a level of `side` blocks a side.
#[inline(always)]
fn outside(s: V3, k: i64x4, side: i64x4) -> m64x4 {
    s.or_m64x4(s.cmp_lt_i64x4(k, s.splat_i64x4(0)), s.cmp_ge_i64x4(k, side))
}

/// The parent of a block index, `k >> 1` (any value for `k < 0`,
/// which is off the map).
#[inline(always)]
fn parent(s: V3, k: i64x4) -> i64x4 {
    cast(s.shr_const_u64x4::<1>(cast(k)))
}

/// One step of every lane's walk (see [`MaxMips::first_hit`]): the
/// busy lanes whose walk ended (bit `l` for lane `l`), and the hits of
/// those that met their cell (the others ended without a hit).
#[inline(always)]
pub(super) fn step(
    simd: V3,
    mips: &MaxMips,
    height: &TiledGrid,
    top: i64,
    rays: &Rays,
    walks: &mut Walks,
) -> (i32, [Option<f64>; LANES]) {
    let s = simd;
    let r = &rays.vectors();
    let w = &mut walks.vectors();
    // The level's blocks per side, `⌈n / 2^level⌉` for the map's `n`
    // cells (each level halves the one below, rounding up), the level
    // below's, and the block's place in its level's tiles.
    let one = s.splat_i64x4(1);
    let zero = s.splat_i64x4(0);
    let down = s.wrapping_sub_i64x4(w.level, one);
    let cells = s.splat_i64x4(signed(mips.sides[0]));
    let side = blocks(s, cells, w.level);
    let side_below = blocks(
        s,
        cells,
        s.select_i64x4(s.cmp_lt_i64x4(down, zero), zero, down),
    );
    let index = tiled_index(s, side, w.i, w.j);
    // The block's highest point: the stored level's, or at level 0
    // the cell's highest corner.
    let (level, index, i, j): ([i64; LANES], [i64; LANES], [i64; LANES], [i64; LANES]) =
        (cast(w.level), cast(index), cast(w.i), cast(w.j));
    let mut highest = [0.0f64; LANES];
    for l in 0..LANES {
        highest[l] = f64::from(match level[l] {
            0 => Corners::of(height, i[l] as usize, j[l] as usize).highest(),
            k => mips.levels[k as usize - 1].at_index(index[l] as usize),
        });
    }
    let highest: f64x4 = cast(highest);
    // Where each ray leaves its block (`MapRay::exit`), clamped to the
    // span, and whether it passes below the block's highest point
    // (`MapRay::lowest`).
    let tu = across(s, w.i, w.level, r.upper_u, r.u0, r.inv_du, r.fixed_u);
    let tv = across(s, w.j, w.level, r.upper_v, r.v0, r.inv_dv, r.fixed_v);
    let across_u = s.cmp_le_f64x4(tu, tv);
    let across_v = s.cmp_le_f64x4(tv, tu);
    // `tu.min(tv)` as Rust has it: `tu` where `tv` is NaN (an infinite
    // reciprocal times a zero distance), which the processor's `min` would
    // not give.
    let exit = s.select_f64x4(s.cmp_eq_f64x4(tv, tv), s.min_f64x4(tu, tv), tu);
    let exit = s.select_f64x4(
        s.cmp_lt_f64x4(exit, w.t),
        w.t,
        s.select_f64x4(s.cmp_gt_f64x4(exit, w.t_end), w.t_end, exit),
    );
    let lowest = s.add_f64x4(
        r.z0,
        s.mul_f64x4(r.dz, s.select_f64x4(r.descending, exit, w.t)),
    );
    let below = s.cmp_le_f64x4(lowest, highest);
    let at_cell = s.cmp_eq_i64x4(w.level, zero);
    // The cells met: a ray below its cell's highest corner at level 0.
    let meeting = s.and_m64x4(w.busy, s.and_m64x4(below, at_cell));
    let mut met = [None; LANES];
    if s.avx._mm256_movemask_pd(cast(meeting)) != 0 {
        let meeting: [u64; LANES] = cast(meeting);
        let (t, exit): ([f64; LANES], [f64; LANES]) = (cast(w.t), cast(exit));
        for l in 0..LANES {
            if meeting[l] != 0 {
                let (i, j) = (i[l] as usize, j[l] as usize);
                let corners = Corners::of(height, i, j);
                met[l] = cell_hit(&corners, &rays.get(l), i, j, t[l], exit[l]);
            }
        }
    }
    // A closer look: one level down, into the child the ray is in
    // (`child`).
    let closer = s.andnot_m64x4(at_cell, below);
    let last = s.wrapping_sub_i64x4(side_below, one);
    let ci = child(
        s,
        s.add_f64x4(r.u0, s.mul_f64x4(r.du, w.t)),
        r.rising_u,
        w.i,
        down,
        last,
    );
    let cj = child(
        s,
        s.add_f64x4(r.v0, s.mul_f64x4(r.dv, w.t)),
        r.rising_v,
        w.j,
        down,
        last,
    );
    // On to the next block (`step`), up a level past the parent.
    let ni = s.select_i64x4(across_u, s.wrapping_add_i64x4(w.i, r.step_u), w.i);
    let nj = s.select_i64x4(across_v, s.wrapping_add_i64x4(w.j, r.step_v), w.j);
    let off_map = s.or_m64x4(outside(s, ni, side), outside(s, nj, side));
    let crossed = s.or_m64x4(
        s.not_m64x4(s.cmp_eq_i64x4(parent(s, ni), parent(s, w.i))),
        s.not_m64x4(s.cmp_eq_i64x4(parent(s, nj), parent(s, w.j))),
    );
    let up = s.and_m64x4(crossed, s.cmp_lt_i64x4(w.level, s.splat_i64x4(top)));
    let finished = s.or_m64x4(s.cmp_ge_f64x4(exit, w.t_end), off_map);
    let moved_i = s.select_i64x4(up, parent(s, ni), ni);
    let moved_j = s.select_i64x4(up, parent(s, nj), nj);
    let moved_level = s.select_i64x4(up, s.wrapping_add_i64x4(w.level, one), w.level);
    // Idle lanes stay on the block (0, 0) of level 0, in the map.
    w.t = s.select_f64x4(closer, w.t, exit);
    w.level = s.select_i64x4(w.busy, s.select_i64x4(closer, down, moved_level), zero);
    w.i = s.select_i64x4(w.busy, s.select_i64x4(closer, ci, moved_i), zero);
    w.j = s.select_i64x4(w.busy, s.select_i64x4(closer, cj, moved_j), zero);
    // The lanes whose walk ended: a cell met, or past the span or the
    // map's edge while moving on.
    let gone = s.and_m64x4(w.busy, s.andnot_m64x4(closer, finished));
    let gone = s.avx._mm256_movemask_pd(cast(gone));
    let met_lanes = met
        .iter()
        .enumerate()
        .fold(0, |m, (l, hit)| m | (i32::from(hit.is_some()) << l));
    walks.store(w);
    (gone | met_lanes, met)
}
