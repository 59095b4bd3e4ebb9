//! A square grid of `f32` samples stored in 8 × 8 tiles, so that a
//! bilinear lookup's four samples, and the samples a ray visits next, lie
//! in one or two cache lines whatever the ray's direction (a row-major map
//! of the testbed puts neighbouring rows 14 kB apart).

/// Samples per tile side.
const TILE: usize = 8;

/// A square grid of `side × side` samples in 8 × 8 tiles.
pub(super) struct TiledGrid {
    side: usize,
    tiles_per_side: usize,
    data: Vec<f32>,
}

impl TiledGrid {
    /// The grid of `side × side` samples from their row-major values.
    pub(super) fn from_row_major(side: usize, values: &[f32]) -> Self {
        let tiles_per_side = side.div_ceil(TILE);
        let mut data = vec![0.0; tiles_per_side * tiles_per_side * TILE * TILE];
        let grid = Self {
            side,
            tiles_per_side,
            data: Vec::new(),
        };
        for j in 0..side {
            for i in 0..side {
                data[grid.index(i, j)] = values[j * side + i];
            }
        }
        Self { data, ..grid }
    }

    fn index(&self, i: usize, j: usize) -> usize {
        Self::index_of(self.tiles_per_side, i, j)
    }

    /// The sample at column `i`, row `j`.
    #[inline]
    pub(super) fn at(&self, i: usize, j: usize) -> f32 {
        self.data[self.index(i, j)]
    }

    /// The sample at `index` of the tiled order ([`Self::index_of`]).
    #[inline]
    pub(super) fn at_index(&self, index: usize) -> f32 {
        self.data[index]
    }

    /// Where the sample at column `i`, row `j` lies in the tiled order of
    /// a grid of `tiles_per_side` tiles a side: `((j / 8) · tiles_per_side
    /// + i / 8) · 64 + (j % 8) · 8 + i % 8`.
    pub(super) fn index_of(tiles_per_side: usize, i: usize, j: usize) -> usize {
        ((j / TILE) * tiles_per_side + i / TILE) * TILE * TILE + (j % TILE) * TILE + i % TILE
    }

    /// Samples per side.
    pub(super) fn side(&self) -> usize {
        self.side
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_sample_comes_back_from_its_tile() {
        let side = 19;
        let values: Vec<f32> = (0..side * side).map(|k| k as f32).collect();
        let grid = TiledGrid::from_row_major(side, &values);
        for j in 0..side {
            for i in 0..side {
                assert_eq!(grid.at(i, j), values[j * side + i]);
            }
        }
    }
}
