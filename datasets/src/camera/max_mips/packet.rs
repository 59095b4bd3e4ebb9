//! Rays cast over the maximum mipmap four at a time, in lock step, on the
//! processor's 256-bit vectors where it has them (x86-64 with AVX2, found
//! at run time; elsewhere one ray at a time). Each step makes, for every
//! lane's ray, the decisions of [`MaxMips::first_hit`]'s walk (look
//! closer, meet the cell, move on, go up a level) as selects rather than
//! branches, so no lane's decision is mispredicted; a lane whose ray ends
//! takes the next ray. Every lane does the single-ray walk's operations
//! in the same order, so each hit is the same float.

use super::super::tiled::TiledGrid;
use super::MaxMips;

/// One ray to cast: from `origin` along `dir` (metres, the map's origin at
/// `(0, 0)`) over the lengths `span`.
#[derive(Debug, Clone, Copy)]
pub(in crate::camera) struct RayQuery {
    /// The ray's origin (m).
    pub origin: [f64; 3],
    /// The ray's direction.
    pub dir: [f64; 3],
    /// The lengths `[t_start, t_end]` to search.
    pub span: [f64; 2],
}

impl MaxMips {
    /// [`MaxMips::first_hit`] of every query, into `hits` (as long as
    /// `queries`).
    pub(in crate::camera) fn first_hits(
        &self,
        height: &TiledGrid,
        cell_m: f64,
        queries: &[RayQuery],
        hits: &mut [Option<f64>],
    ) {
        #[cfg(target_arch = "x86_64")]
        if let Some(simd) = pulp::x86::V3::try_new() {
            simd.vectorize(lanes::PacketWalk {
                simd,
                mips: self,
                height,
                cell_m,
                queries,
                hits,
            });
            return;
        }
        for (q, hit) in queries.iter().zip(hits) {
            *hit = self.first_hit(height, cell_m, q.origin, q.dir, q.span[0], q.span[1]);
        }
    }
}

#[cfg(target_arch = "x86_64")]
mod lanes {
    use pulp::x86::V3;
    use pulp::{cast, f64x4, i64x4, m64x4, u64x4};

    use super::super::super::tiled::TiledGrid;
    use super::super::{Corners, MapRay, MaxMips, START_LEVEL, cell_hit};
    use super::RayQuery;

    /// Rays walked side by side.
    const LANES: usize = 4;

    /// An all-ones (true) or all-zeros lane mask.
    fn mask(b: bool) -> u64 {
        if b { u64::MAX } else { 0 }
    }

    /// The lanes' rays, one array element per lane: the walk's constants.
    #[derive(Default, Clone, Copy)]
    struct Rays {
        u0: [f64; LANES],
        v0: [f64; LANES],
        z0: [f64; LANES],
        du: [f64; LANES],
        dv: [f64; LANES],
        dz: [f64; LANES],
        inv_du: [f64; LANES],
        inv_dv: [f64; LANES],
        /// Masks: the ray keeps its u (v) coordinate; it moves up (or
        /// keeps) u (v); it descends.
        fixed_u: [u64; LANES],
        fixed_v: [u64; LANES],
        rising_u: [u64; LANES],
        rising_v: [u64; LANES],
        descending: [u64; LANES],
        /// 1 where the ray moves up the axis (its exit boundary is the
        /// block's upper one), else 0.
        upper_u: [i64; LANES],
        upper_v: [i64; LANES],
        /// The block index's step along the axis: +1 or −1.
        step_u: [i64; LANES],
        step_v: [i64; LANES],
    }

    /// The lanes' walks: the span left and the block, and which are busy.
    #[derive(Default, Clone, Copy)]
    struct Walks {
        t: [f64; LANES],
        t_end: [f64; LANES],
        level: [i64; LANES],
        i: [i64; LANES],
        j: [i64; LANES],
        busy: [u64; LANES],
        query: [usize; LANES],
    }

    /// The walks on vectors.
    #[derive(Clone, Copy)]
    struct WalkVectors {
        t: f64x4,
        t_end: f64x4,
        level: i64x4,
        i: i64x4,
        j: i64x4,
        busy: m64x4,
    }

    /// The rays on vectors.
    #[derive(Clone, Copy)]
    struct RayVectors {
        u0: f64x4,
        v0: f64x4,
        z0: f64x4,
        du: f64x4,
        dv: f64x4,
        dz: f64x4,
        inv_du: f64x4,
        inv_dv: f64x4,
        fixed_u: m64x4,
        fixed_v: m64x4,
        rising_u: m64x4,
        rising_v: m64x4,
        descending: m64x4,
        upper_u: i64x4,
        upper_v: i64x4,
        step_u: i64x4,
        step_v: i64x4,
    }

    impl Rays {
        /// Puts `ray` in lane `l`.
        fn set(&mut self, l: usize, ray: &MapRay) {
            self.u0[l] = ray.u0;
            self.v0[l] = ray.v0;
            self.z0[l] = ray.z0;
            self.du[l] = ray.du;
            self.dv[l] = ray.dv;
            self.dz[l] = ray.dz;
            self.inv_du[l] = ray.inv_du;
            self.inv_dv[l] = ray.inv_dv;
            self.fixed_u[l] = mask(ray.du == 0.0);
            self.fixed_v[l] = mask(ray.dv == 0.0);
            self.rising_u[l] = mask(ray.du >= 0.0);
            self.rising_v[l] = mask(ray.dv >= 0.0);
            self.descending[l] = mask(ray.dz < 0.0);
            self.upper_u[l] = i64::from(ray.du > 0.0);
            self.upper_v[l] = i64::from(ray.dv > 0.0);
            self.step_u[l] = if ray.du > 0.0 { 1 } else { -1 };
            self.step_v[l] = if ray.dv > 0.0 { 1 } else { -1 };
        }

        /// Lane `l`'s ray.
        fn get(&self, l: usize) -> MapRay {
            MapRay {
                u0: self.u0[l],
                v0: self.v0[l],
                z0: self.z0[l],
                du: self.du[l],
                dv: self.dv[l],
                dz: self.dz[l],
                inv_du: self.inv_du[l],
                inv_dv: self.inv_dv[l],
            }
        }

        #[inline(always)]
        fn vectors(&self) -> RayVectors {
            RayVectors {
                u0: cast(self.u0),
                v0: cast(self.v0),
                z0: cast(self.z0),
                du: cast(self.du),
                dv: cast(self.dv),
                dz: cast(self.dz),
                inv_du: cast(self.inv_du),
                inv_dv: cast(self.inv_dv),
                fixed_u: cast(self.fixed_u),
                fixed_v: cast(self.fixed_v),
                rising_u: cast(self.rising_u),
                rising_v: cast(self.rising_v),
                descending: cast(self.descending),
                upper_u: cast(self.upper_u),
                upper_v: cast(self.upper_v),
                step_u: cast(self.step_u),
                step_v: cast(self.step_v),
            }
        }
    }

    impl Walks {
        #[inline(always)]
        fn vectors(&self) -> WalkVectors {
            WalkVectors {
                t: cast(self.t),
                t_end: cast(self.t_end),
                level: cast(self.level),
                i: cast(self.i),
                j: cast(self.j),
                busy: cast(self.busy),
            }
        }

        #[inline(always)]
        fn store(&mut self, v: &WalkVectors) {
            self.t = cast(v.t);
            self.t_end = cast(v.t_end);
            self.level = cast(v.level);
            self.i = cast(v.i);
            self.j = cast(v.j);
            self.busy = cast(v.busy);
        }
    }

    /// A block or level index (non-negative, far below 2⁶³) as `i64`.
    fn signed(k: usize) -> i64 {
        i64::try_from(k).unwrap_or(i64::MAX)
    }

    /// The walk of every query, as a `pulp` operation (inlined into a
    /// function compiled for AVX2).
    pub(super) struct PacketWalk<'a> {
        pub simd: V3,
        pub mips: &'a MaxMips,
        pub height: &'a TiledGrid,
        pub cell_m: f64,
        pub queries: &'a [RayQuery],
        pub hits: &'a mut [Option<f64>],
    }

    impl pulp::NullaryFnOnce for PacketWalk<'_> {
        type Output = ();

        #[inline(always)]
        fn call(self) {
            let PacketWalk {
                simd,
                mips,
                height,
                cell_m,
                queries,
                hits,
            } = self;
            let top = signed(mips.sides.len() - 1);
            let mut next = 0;
            let mut packets = [(); PACKETS].map(|()| {
                let mut rays = Rays::default();
                let mut walks = Walks::default();
                for l in 0..LANES {
                    refill(
                        mips, &mut rays, &mut walks, l, cell_m, queries, hits, &mut next,
                    );
                }
                Packet {
                    ray_v: rays.vectors(),
                    walk_v: walks.vectors(),
                    rays,
                    walks,
                }
            });
            while packets.iter().any(|p| walks_busy(simd, &p.walk_v)) {
                for p in &mut packets {
                    let (ended, met) =
                        step(simd, mips, height, top, &p.rays, &p.ray_v, &mut p.walk_v);
                    if ended != 0 {
                        p.walks.store(&p.walk_v);
                        for (l, hit) in met.into_iter().enumerate() {
                            if ended & (1 << l) != 0 {
                                hits[p.walks.query[l]] = hit;
                                refill(
                                    mips,
                                    &mut p.rays,
                                    &mut p.walks,
                                    l,
                                    cell_m,
                                    queries,
                                    hits,
                                    &mut next,
                                );
                            }
                        }
                        p.ray_v = p.rays.vectors();
                        p.walk_v = p.walks.vectors();
                    }
                }
            }
        }
    }

    /// Packets walked in turn, so that one's loads and arithmetic overlap
    /// the other's (each step waits on its own lookups).
    const PACKETS: usize = 3;

    /// A packet of lanes: its rays and walks, in arrays and on vectors.
    struct Packet {
        rays: Rays,
        walks: Walks,
        ray_v: RayVectors,
        walk_v: WalkVectors,
    }

    /// Blocks per side of `level` over `cells` cells a side: `⌈cells /
    /// 2^level⌉` (each level halves the one below, rounding up).
    #[inline(always)]
    fn blocks(s: V3, cells: i64x4, level: i64x4) -> i64x4 {
        let one = s.splat_i64x4(1);
        let size = shl(s, one, level);
        let round_up = s.wrapping_sub_i64x4(s.wrapping_add_i64x4(cells, size), one);
        cast(s.shr_dyn_u64x4(cast(round_up), cast(level)))
    }

    /// Whether any lane is busy.
    #[inline(always)]
    fn walks_busy(simd: V3, w: &WalkVectors) -> bool {
        simd.avx._mm256_movemask_pd(cast(w.busy)) != 0
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

    /// Gives lane `l` the next query whose ray meets the map (answering
    /// those that miss it on the way), or leaves it idle at the end.
    #[allow(clippy::too_many_arguments)]
    fn refill(
        mips: &MaxMips,
        rays: &mut Rays,
        walks: &mut Walks,
        l: usize,
        cell_m: f64,
        queries: &[RayQuery],
        hits: &mut [Option<f64>],
        next: &mut usize,
    ) {
        while let Some(q) = queries.get(*next) {
            let k = *next;
            *next += 1;
            if let Some(walk) = mips.walk(START_LEVEL, cell_m, q.origin, q.dir, q.span) {
                rays.set(l, &walk.ray);
                walks.t[l] = walk.t;
                walks.t_end[l] = walk.t_end;
                walks.level[l] = signed(walk.level);
                walks.i[l] = signed(walk.i);
                walks.j[l] = signed(walk.j);
                walks.busy[l] = u64::MAX;
                walks.query[l] = k;
                return;
            }
            hits[k] = None;
        }
        // Idle, on a valid block so that the lane's reads stay in the map.
        walks.busy[l] = 0;
        walks.level[l] = 0;
        walks.i[l] = 0;
        walks.j[l] = 0;
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
    fn step(
        simd: V3,
        mips: &MaxMips,
        height: &TiledGrid,
        top: i64,
        rays: &Rays,
        r: &RayVectors,
        w: &mut WalkVectors,
    ) -> (i32, [Option<f64>; LANES]) {
        let s = simd;
        // The level's blocks per side, `⌈n / 2^level⌉` for the map's `n`
        // cells (each level halves the one below, rounding up), the level
        // below's, and the block's place in its level's tiles.
        let one = s.splat_i64x4(1);
        let zero_i = s.splat_i64x4(0);
        let down = s.wrapping_sub_i64x4(w.level, one);
        let cells = s.splat_i64x4(signed(mips.sides[0]));
        let side = blocks(s, cells, w.level);
        let side_below = blocks(
            s,
            cells,
            s.select_i64x4(s.cmp_lt_i64x4(down, zero_i), zero_i, down),
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
        let exit = s.min_f64x4(tu, tv);
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
        let zero = s.splat_i64x4(0);
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
        (gone | met_lanes, met)
    }
}

#[cfg(test)]
mod tests {
    use super::super::super::tiled::TiledGrid;
    use super::super::MaxMips;
    use super::RayQuery;

    /// A 64-bit LCG's uniform draws in [0, 1).
    fn uniform(state: &mut u64) -> f64 {
        *state = state
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (*state >> 11) as f64 / (1u64 << 53) as f64
    }

    #[test]
    fn the_packets_hits_are_the_single_rays_to_the_bit() {
        // A rough 181 × 181 map (180 cells a side, 9 levels) of 1 cm cells.
        let n = 181;
        let mut state = 11u64;
        let values: Vec<f32> = (0..n * n)
            .map(|k| {
                let (x, y) = ((k % n) as f64, (k / n) as f64);
                let bump = 0.05 * (0.07 * x).sin() * (0.05 * y).cos();
                (bump + 0.01 * uniform(&mut state)) as f32
            })
            .collect();
        let height = TiledGrid::from_row_major(n, &values);
        let mips = MaxMips::build(&height);
        let cell_m = 0.01;
        let mut queries = Vec::new();
        for k in 0..4001 {
            let mut origin = [
                -0.2 + 2.2 * uniform(&mut state),
                -0.2 + 2.2 * uniform(&mut state),
                0.02 + 0.3 * uniform(&mut state),
            ];
            let (azimuth, down) = (
                std::f64::consts::TAU * uniform(&mut state),
                -0.1 + 1.0 * uniform(&mut state),
            );
            let mut dir = [
                down.cos() * azimuth.cos(),
                down.cos() * azimuth.sin(),
                -down.sin(),
            ];
            // Rays along an axis, straight down, and from cell corners.
            match k % 7 {
                0 => dir[0] = 0.0,
                1 => dir[1] = -0.0,
                2 => dir = [0.0, 0.0, -1.0],
                3 => origin = [0.37, 1.21, origin[2]],
                _ => {}
            }
            queries.push(RayQuery {
                origin,
                dir,
                span: [0.0, 0.5 + 3.0 * uniform(&mut state)],
            });
        }
        let mut hits = vec![Some(-1.0); queries.len()];
        mips.first_hits(&height, cell_m, &queries, &mut hits);
        let (mut met, mut missed) = (0, 0);
        for (q, hit) in queries.iter().zip(&hits) {
            let single = mips.first_hit(&height, cell_m, q.origin, q.dir, q.span[0], q.span[1]);
            assert_eq!(
                hit.map(f64::to_bits),
                single.map(f64::to_bits),
                "{q:?}: {hit:?} against {single:?}"
            );
            if hit.is_some() {
                met += 1;
            } else {
                missed += 1;
            }
        }
        assert!(met > 1500 && missed > 500, "{met} hits, {missed} misses");
        eprintln!("{met} hits, {missed} misses");
        // Fewer rays than lanes, and none.
        let mut few = vec![None; 3];
        mips.first_hits(&height, cell_m, &queries[..3], &mut few);
        assert_eq!(few, hits[..3]);
        mips.first_hits(&height, cell_m, &[], &mut []);
    }
}
