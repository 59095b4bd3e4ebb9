//! The ground the camera sees, precomputed once per testbed on a square
//! grid over the test area: its height (the simulator's terrain, plus each
//! soil's micro-relief and the stones lying on it) and its radiance under
//! the lab's lighting (albedo times ambient plus the key light's cosine,
//! with cast shadows). Rendering a view then only marches rays over these
//! maps. The wheels still roll on the simulator's terrain alone: the
//! relief and the stones are seen, not felt.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

use super::convert::{as_f64, truncate};
use super::look::{SceneSpec, SoilLook};
use super::max_mips::{MaxMips, RayQuery};
use super::noise::{mix, octaves};
use super::tiled::TiledGrid;
use crate::TestbedError;
use crate::sim::soil::SoilMap;
use crate::sim::terrain::Terrain;

/// The random stream of the camera's scene (the stones), apart from the
/// simulator's streams, so the runs are the same with or without a camera.
const SCENE_STREAM: u64 = 1 << 41;

/// A stone: a half-ellipsoid on the ground.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Stone {
    x: f64,
    y: f64,
    radius: f64,
    height: f64,
    albedo: f64,
}

impl Stone {
    /// Its height above the ground at `(x, y)`, or `None` outside it.
    fn bump(&self, x: f64, y: f64) -> Option<f64> {
        let d2 = ((x - self.x).powi(2) + (y - self.y).powi(2)) / (self.radius * self.radius);
        (d2 < 1.0).then(|| self.height * (1.0 - d2).sqrt())
    }
}

/// The stones, bucketed in square cells for lookup.
struct StoneField {
    stones: Vec<Stone>,
    cell_m: f64,
    cells_per_side: usize,
    cells: Vec<Vec<u32>>,
}

impl StoneField {
    fn new(stones: Vec<Stone>, size_m: f64) -> Self {
        let cell_m = 0.1;
        let cells_per_side = (size_m / cell_m).ceil() as usize + 1;
        let mut field = Self {
            stones: Vec::new(),
            cell_m,
            cells_per_side,
            cells: vec![Vec::new(); cells_per_side * cells_per_side],
        };
        for (k, s) in stones.iter().enumerate() {
            for cy in field.index(s.y - s.radius)..=field.index(s.y + s.radius) {
                for cx in field.index(s.x - s.radius)..=field.index(s.x + s.radius) {
                    field.cells[cy * cells_per_side + cx].push(k as u32);
                }
            }
        }
        field.stones = stones;
        field
    }

    /// The cell along one axis of the coordinate `v` (m), clamped.
    fn index(&self, v: f64) -> usize {
        ((v / self.cell_m).floor().max(0.0) as usize).min(self.cells_per_side - 1)
    }

    /// The highest stone over `(x, y)`: its height above the ground and
    /// its albedo.
    fn at(&self, x: f64, y: f64) -> Option<(f64, f64)> {
        self.cells[self.index(y) * self.cells_per_side + self.index(x)]
            .iter()
            .filter_map(|&k| {
                let s = &self.stones[k as usize];
                s.bump(x, y).map(|h| (h, s.albedo))
            })
            .max_by(|a, b| a.0.total_cmp(&b.0))
    }
}

/// Draws every soil's stones: for each soil and size class, `per_m2 ·
/// area` candidates uniform over the test area, kept where that soil is.
/// Each (soil, class) draws from a stream of its own, and every candidate
/// draws the same four numbers, kept or not, so one class's settings never
/// move another's stones.
fn scatter_stones(spec: &SceneSpec, soils: &SoilMap, size_m: f64, seed: u64) -> Vec<Stone> {
    let mut stones = Vec::new();
    let looks = [
        ("compact", &spec.compact),
        ("loose_sand", &spec.loose_sand),
        ("gravel", &spec.gravel),
    ];
    for (soil, (name, look)) in looks.into_iter().enumerate() {
        for (k, class) in look.stones.iter().enumerate() {
            let mut rng = ChaCha8Rng::seed_from_u64(seed);
            rng.set_stream(SCENE_STREAM + (soil as u64) * 256 + k as u64);
            let count = (class.per_m2 * size_m * size_m).round() as usize;
            for _ in 0..count {
                let (u, v, r, a): (f64, f64, f64, f64) =
                    (rng.random(), rng.random(), rng.random(), rng.random());
                let (x, y) = (u * size_m, v * size_m);
                if soils.soil_at(x, y).name != name {
                    continue;
                }
                let [r0, r1] = class.radius_m;
                let radius = r0 + (r1 - r0) * r;
                let [a0, a1] = class.albedo;
                stones.push(Stone {
                    x,
                    y,
                    radius,
                    height: class.height_ratio * radius,
                    albedo: a0 + (a1 - a0) * a,
                });
            }
        }
    }
    stones
}

/// How a ray's first hit is found (see [`GroundMaps::first_hit`]).
enum RayPlan {
    /// Without the map: the floor's hit, or none.
    Known(Option<f64>),
    /// By a walk over the map's mipmap, else the floor beyond the area.
    Walk {
        query: RayQuery,
        floor_after: Option<f64>,
    },
}

/// The precomputed height and radiance of the test area.
pub struct GroundMaps {
    size_m: f64,
    cell_m: f64,
    /// Samples per side (`size / cell + 1`).
    n: usize,
    height: TiledGrid,
    /// The height map's maximum mipmap, for casting rays.
    mips: MaxMips,
    radiance: TiledGrid,
    /// The highest point of the area (m).
    pub max_height_m: f64,
    /// The lab floor's radiance beyond the area.
    pub floor_radiance: f64,
    /// The radiance of a ray that meets nothing.
    pub background: f64,
}

impl GroundMaps {
    /// Builds the maps of the testbed of `terrain` and `soils` as `spec`
    /// says, its stones drawn from `seed`'s scene stream.
    ///
    /// # Errors
    /// [`TestbedError::InvalidConfig`] naming a bad setting of `spec`, or
    /// a soil with no look.
    pub fn build(
        terrain: &Terrain,
        soils: &SoilMap,
        spec: &SceneSpec,
        seed: u64,
    ) -> Result<Self, TestbedError> {
        spec.validate("camera.scene")?;
        let looks: Vec<&SoilLook> = soils
            .soils()
            .iter()
            .map(|s| spec.look_of(s))
            .collect::<Result<_, _>>()?;
        let size_m = terrain.size_m();
        let n = (size_m / spec.map_cell_m).round() as usize + 1;
        let cell_m = size_m / (n - 1) as f64;
        let stones = StoneField::new(scatter_stones(spec, soils, size_m, seed), size_m);
        let key = mix(seed ^ SCENE_STREAM);
        // Height and albedo, row by row.
        let rows: Vec<(Vec<f32>, Vec<f32>)> = (0..n)
            .into_par_iter()
            .map(|j| {
                let y = j as f64 * cell_m;
                let mut heights = Vec::with_capacity(n);
                let mut albedos = Vec::with_capacity(n);
                for i in 0..n {
                    let x = i as f64 * cell_m;
                    let soil = soils.soil_index_at(x, y);
                    let look = looks[soil];
                    let soil_key = mix(key ^ soil as u64);
                    let relief =
                        octaves(soil_key, x, y, look.relief_cell_m, &look.relief_octaves_m);
                    let ground = terrain.height(x, y) + relief;
                    let texture = octaves(
                        mix(soil_key ^ 1),
                        x,
                        y,
                        look.albedo_cell_m,
                        &look.albedo_octaves,
                    );
                    let (height, albedo) = match stones.at(x, y) {
                        // Stones are mottled at the finest two octaves.
                        Some((bump, albedo)) => {
                            let mottle = octaves(mix(soil_key ^ 2), x, y, 0.01, &[0.08, 0.06]);
                            (ground + bump, albedo + mottle)
                        }
                        None => (ground, look.albedo + texture),
                    };
                    heights.push(height as f32);
                    albedos.push(albedo.clamp(0.0, 1.0) as f32);
                }
                (heights, albedos)
            })
            .collect();
        let mut height = Vec::with_capacity(n * n);
        let mut albedo = Vec::with_capacity(n * n);
        for (h, a) in rows {
            height.extend(h);
            albedo.extend(a);
        }
        let max_height_m = height
            .iter()
            .fold(f64::NEG_INFINITY, |m, &h| m.max(f64::from(h)));
        let height = TiledGrid::from_row_major(n, &height);
        let mips = MaxMips::build(&height);
        let mut maps = Self {
            size_m,
            cell_m,
            n,
            height,
            mips,
            radiance: TiledGrid::from_row_major(0, &[]),
            max_height_m,
            floor_radiance: spec.floor_albedo
                * (spec.lighting.ambient
                    + spec.lighting.key * spec.lighting.key_elevation_rad.sin()),
            background: spec.background,
        };
        maps.radiance = TiledGrid::from_row_major(n, &maps.shade(&albedo, spec));
        Ok(maps)
    }

    /// Radiance of every sample: `albedo · (ambient + key · max(0, n·l) ·
    /// lit)`, the normal from central differences, `lit` from a march
    /// towards the key light.
    fn shade(&self, albedo: &[f32], spec: &SceneSpec) -> Vec<f32> {
        let n = self.n;
        let l = spec.lighting;
        let towards = l.towards_key();
        let rows: Vec<Vec<f32>> = (0..n)
            .into_par_iter()
            .map(|j| {
                (0..n)
                    .map(|i| {
                        let h = |i: usize, j: usize| f64::from(self.height.at(i, j));
                        let (i0, i1) = (i.saturating_sub(1), (i + 1).min(n - 1));
                        let (j0, j1) = (j.saturating_sub(1), (j + 1).min(n - 1));
                        let dx = (h(i1, j) - h(i0, j)) / ((i1 - i0) as f64 * self.cell_m);
                        let dy = (h(i, j1) - h(i, j0)) / ((j1 - j0) as f64 * self.cell_m);
                        let normal = nalgebra::Vector3::new(-dx, -dy, 1.0).normalize();
                        let cosine = normal.dot(&towards).max(0.0);
                        let lit = if cosine > 0.0 && self.lit(i, j, &towards) {
                            1.0
                        } else {
                            0.0
                        };
                        let a = f64::from(albedo[j * n + i]);
                        (a * (l.ambient + l.key * cosine * lit)) as f32
                    })
                    .collect()
            })
            .collect();
        rows.concat()
    }

    /// Whether the sample `(i, j)` sees the key light: a march towards it
    /// until it rises above the highest ground.
    fn lit(&self, i: usize, j: usize, towards: &nalgebra::Vector3<f64>) -> bool {
        let (x0, y0) = (i as f64 * self.cell_m, j as f64 * self.cell_m);
        let z0 = f64::from(self.height.at(i, j)) + 1e-4;
        let horizontal = (towards.x.powi(2) + towards.y.powi(2)).sqrt();
        if horizontal < 1e-9 {
            return true;
        }
        let rise = towards.z / horizontal;
        let mut s = 1.5 * self.cell_m;
        while s < 3.0 {
            let z = z0 + rise * s;
            if z > self.max_height_m {
                return true;
            }
            let (x, y) = (
                x0 + towards.x / horizontal * s,
                y0 + towards.y / horizontal * s,
            );
            match self.height_in(x, y) {
                Some(h) if h > z => return false,
                Some(h) => s += ((z - h) / (rise + 1.5)).max(self.cell_m),
                None => return true,
            }
        }
        true
    }

    fn bilinear(&self, data: &TiledGrid, x: f64, y: f64) -> Option<f64> {
        if !(x >= 0.0 && y >= 0.0 && x <= self.size_m && y <= self.size_m) {
            return None;
        }
        let (u, v) = (x / self.cell_m, y / self.cell_m);
        let last = self.n - 2;
        let (i, j) = (truncate(u).min(last), truncate(v).min(last));
        let (tx, ty) = (u - as_f64(i), v - as_f64(j));
        let at = |i: usize, j: usize| f64::from(data.at(i, j));
        let top = at(i, j) + (at(i + 1, j) - at(i, j)) * tx;
        let bottom = at(i, j + 1) + (at(i + 1, j + 1) - at(i, j + 1)) * tx;
        Some(top + (bottom - top) * ty)
    }

    /// The ground's height at `(x, y)` inside the test area.
    pub fn height_in(&self, x: f64, y: f64) -> Option<f64> {
        self.bilinear(&self.height, x, y)
    }

    /// The ground's height at `(x, y)`: the map's inside the area, the
    /// lab floor's (0) outside.
    pub fn height(&self, x: f64, y: f64) -> f64 {
        self.height_in(x, y).unwrap_or(0.0)
    }

    /// The radiance of the ground at `(x, y)`.
    pub fn radiance(&self, x: f64, y: f64) -> f64 {
        self.bilinear(&self.radiance, x, y)
            .unwrap_or(self.floor_radiance)
    }

    /// The first length `t` in `[t_start, t_end]` (m) at which the ray
    /// from `origin` along the unit `dir` meets the ground: the map's
    /// bilinear surface inside the area, the lab floor (height 0) outside.
    pub fn first_hit(
        &self,
        origin: &nalgebra::Point3<f64>,
        dir: &nalgebra::Vector3<f64>,
        t_start: f64,
        t_end: f64,
    ) -> Option<f64> {
        match self.plan(origin, dir, t_start, t_end) {
            RayPlan::Known(hit) => hit,
            RayPlan::Walk { query, floor_after } => self
                .mips
                .first_hit(
                    &self.height,
                    self.cell_m,
                    query.origin,
                    query.dir,
                    query.span[0],
                    query.span[1],
                )
                .or(floor_after),
        }
    }

    /// [`Self::first_hit`] of the rays from `origin` along each of the
    /// unit `dirs`, into `hits` (cleared first): the same numbers, the
    /// rays over the area walked several at a time.
    pub fn first_hits(
        &self,
        origin: &nalgebra::Point3<f64>,
        dirs: &[nalgebra::Vector3<f64>],
        t_start: f64,
        t_end: f64,
        hits: &mut Vec<Option<f64>>,
    ) {
        let plans: Vec<RayPlan> = dirs
            .iter()
            .map(|dir| self.plan(origin, dir, t_start, t_end))
            .collect();
        let queries: Vec<RayQuery> = plans
            .iter()
            .filter_map(|p| match p {
                RayPlan::Walk { query, .. } => Some(*query),
                RayPlan::Known(_) => None,
            })
            .collect();
        let mut walked = vec![None; queries.len()];
        self.mips
            .first_hits(&self.height, self.cell_m, &queries, &mut walked);
        let mut walked = walked.into_iter();
        hits.clear();
        hits.extend(plans.into_iter().map(|p| match p {
            RayPlan::Known(hit) => hit,
            RayPlan::Walk { floor_after, .. } => walked.next().flatten().or(floor_after),
        }));
    }

    /// What [`Self::first_hit`] needs of the map for one ray: nothing (the
    /// ray misses the area, or meets the floor before it), or a walk over
    /// the mipmap, the floor beyond the area answering if the walk meets
    /// nothing.
    fn plan(
        &self,
        origin: &nalgebra::Point3<f64>,
        dir: &nalgebra::Vector3<f64>,
        t_start: f64,
        t_end: f64,
    ) -> RayPlan {
        // The span of the ray over the area, if any.
        let mut span = (t_start, t_end);
        for (o, d) in [(origin.x, dir.x), (origin.y, dir.y)] {
            if d == 0.0 {
                if !(0.0..=self.size_m).contains(&o) {
                    span = (f64::INFINITY, f64::NEG_INFINITY);
                }
                continue;
            }
            let (a, b) = (-o / d, (self.size_m - o) / d);
            span = (span.0.max(a.min(b)), span.1.min(a.max(b)));
        }
        let floor = (dir.z < 0.0)
            .then(|| -origin.z / dir.z)
            .filter(|t| (t_start..=t_end).contains(t));
        if span.0 > span.1 {
            return RayPlan::Known(floor);
        }
        // The floor before the ray enters the area.
        if let Some(t) = floor.filter(|&t| t < span.0) {
            return RayPlan::Known(Some(t));
        }
        // Nothing in the area is met above its highest point.
        let below_top = if dir.z < 0.0 {
            (origin.z - self.max_height_m) / -dir.z
        } else if origin.z > self.max_height_m {
            f64::INFINITY
        } else {
            span.0
        };
        let floor_after = floor.filter(|&t| t > span.1);
        if below_top.max(span.0) <= span.1 {
            RayPlan::Walk {
                query: RayQuery {
                    origin: [origin.x, origin.y, origin.z],
                    dir: [dir.x, dir.y, dir.z],
                    span: [below_top.max(span.0), span.1],
                },
                floor_after,
            }
        } else {
            RayPlan::Known(floor_after)
        }
    }

    /// The side of the test area (m).
    pub fn size_m(&self) -> f64 {
        self.size_m
    }
}
