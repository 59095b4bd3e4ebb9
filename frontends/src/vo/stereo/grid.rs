//! The current frame's keypoints in square cells, for the projection
//! search around each map point's predicted pixel.

use gpodo_vision::stereo::StereoFeatures;

/// The current frame's keypoints bucketed in square cells.
pub(super) struct KeypointGrid {
    cell: f64,
    columns: usize,
    rows: usize,
    cells: Vec<Vec<usize>>,
}

impl KeypointGrid {
    pub(super) fn new(features: &StereoFeatures) -> Self {
        let cell = 16.0;
        let (mut columns, mut rows) = (1, 1);
        for kp in &features.left.keypoints {
            columns = columns.max((f64::from(kp.x) / cell) as usize + 1);
            rows = rows.max((f64::from(kp.y) / cell) as usize + 1);
        }
        let mut cells = vec![Vec::new(); columns * rows];
        for (k, kp) in features.left.keypoints.iter().enumerate() {
            let (i, j) = (
                (f64::from(kp.x) / cell) as usize,
                (f64::from(kp.y) / cell) as usize,
            );
            cells[j * columns + i].push(k);
        }
        Self {
            cell,
            columns,
            rows,
            cells,
        }
    }

    /// The keypoints in the cells that `radius` around `centre` touches.
    pub(super) fn within(&self, centre: [f64; 2], radius: f64) -> impl Iterator<Item = usize> + '_ {
        let span = |c: f64, n: usize| {
            let lo = ((c - radius) / self.cell).floor().max(0.0) as usize;
            let hi = (((c + radius) / self.cell).floor().max(-1.0) + 1.0) as usize;
            lo.min(n)..hi.min(n)
        };
        let (columns, rows) = (span(centre[0], self.columns), span(centre[1], self.rows));
        rows.flat_map(move |j| {
            columns
                .clone()
                .flat_map(move |i| self.cells[j * self.columns + i].iter().copied())
        })
    }
}
