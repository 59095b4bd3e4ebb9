//! The lanes of [`super::MaxMips::first_hits`] on x86-64 with AVX2: the
//! rays and walks of three packets of four lanes, walked in turn so that
//! one packet's lookups overlap another's arithmetic, each lane taking the
//! next ray when its own ends.

mod step;

use pulp::x86::V3;
use pulp::{cast, f64x4, i64x4, m64x4};

use super::RayQuery;
use crate::camera::max_mips::{MapRay, MaxMips, START_LEVEL};
use crate::camera::tiled::TiledGrid;
use step::step;

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
        // What a step moves: the span's start and the block.
        self.t = cast(v.t);
        self.level = cast(v.level);
        self.i = cast(v.i);
        self.j = cast(v.j);
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
            let mut packet = Packet::default();
            for l in 0..LANES {
                refill(mips, &mut packet, l, cell_m, queries, hits, &mut next);
            }
            packet
        });
        while packets.iter().any(|p| p.walks.busy.iter().any(|&b| b != 0)) {
            for p in &mut packets {
                let (ended, met) = step(simd, mips, height, top, &p.rays, &mut p.walks);
                if ended == 0 {
                    continue;
                }
                for (l, hit) in met.into_iter().enumerate() {
                    if ended & (1 << l) != 0 {
                        hits[p.walks.query[l]] = hit;
                        refill(mips, p, l, cell_m, queries, hits, &mut next);
                    }
                }
            }
        }
    }
}

/// Packets walked in turn, so that one's loads and arithmetic overlap
/// the other's (each step waits on its own lookups).
const PACKETS: usize = 3;

/// A packet of lanes: its rays and walks, one array element per lane (a
/// step loads them onto vectors and stores the walks back).
#[derive(Default)]
struct Packet {
    rays: Rays,
    walks: Walks,
}

/// Gives lane `l` the next query whose ray meets the map (answering
/// those that miss it on the way), or leaves it idle at the end.
fn refill(
    mips: &MaxMips,
    packet: &mut Packet,
    l: usize,
    cell_m: f64,
    queries: &[RayQuery],
    hits: &mut [Option<f64>],
    next: &mut usize,
) {
    let walks = &mut packet.walks;
    while let Some(q) = queries.get(*next) {
        let k = *next;
        *next += 1;
        if let Some(walk) = mips.walk(START_LEVEL, cell_m, q.origin, q.dir, q.span) {
            packet.rays.set(l, &walk.ray);
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
