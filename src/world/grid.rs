//! A uniform grid over the plane whose cells list item indices in compressed-row layout (one offsets array,
//! one items array, no per-cell allocation). Items are added by their bounding box, so a point query looks in
//! one cell and a neighbourhood query in a few contiguous runs. Used by the lane index (pieces by bounding box)
//! and by the simulation's conflict-zone search (path samples as points).

use glam::DVec2;

/// Item indices bucketed by grid cell. Within a cell, items are listed in increasing index.
#[derive(Clone, Debug, Default)]
pub(crate) struct CellGrid {
    origin: DVec2,
    cell_m: f64,
    nx: usize,
    ny: usize,
    /// Items of cell `y · nx + x` are `items[starts[c]..starts[c + 1]]`.
    starts: Vec<u32>,
    items: Vec<u32>,
}

impl CellGrid {
    /// A grid over the box `lo`–`hi` (at least 1 m each way) with square cells of `min_cell_m`, doubled until
    /// there are at most `max_cells` cells, holding items `0..count`, each in every cell that its bounding box
    /// `bounds(k)` touches (cells clamped to the grid; `None` leaves the item out). `lo` and `hi` must be finite.
    pub(crate) fn build(
        lo: DVec2,
        hi: DVec2,
        min_cell_m: f64,
        max_cells: f64,
        count: usize,
        bounds: impl Fn(usize) -> Option<(DVec2, DVec2)>,
    ) -> CellGrid {
        let ext = (hi - lo).max(DVec2::splat(1.0));
        let mut cell_m = min_cell_m;
        while (ext.x / cell_m + 1.0) * (ext.y / cell_m + 1.0) > max_cells {
            cell_m *= 2.0;
        }
        let nx = (ext.x / cell_m).floor() as usize + 1;
        let ny = (ext.y / cell_m).floor() as usize + 1;
        let mut grid = CellGrid {
            origin: lo,
            cell_m,
            nx,
            ny,
            starts: vec![0; nx * ny + 1],
            items: Vec::new(),
        };
        let cells = |grid: &CellGrid, k: usize| {
            bounds(k).map(|(a, b)| {
                let ((x0, y0), (x1, y1)) = (grid.clamped_cell(a), grid.clamped_cell(b));
                (x0, y0, x1, y1)
            })
        };
        for k in 0..count {
            if let Some((x0, y0, x1, y1)) = cells(&grid, k) {
                for y in y0..=y1 {
                    for x in x0..=x1 {
                        grid.starts[y * nx + x + 1] += 1;
                    }
                }
            }
        }
        for c in 0..nx * ny {
            grid.starts[c + 1] += grid.starts[c];
        }
        let mut fill = grid.starts.clone();
        grid.items = vec![0; grid.starts[nx * ny] as usize];
        for k in 0..count {
            if let Some((x0, y0, x1, y1)) = cells(&grid, k) {
                for y in y0..=y1 {
                    for x in x0..=x1 {
                        let c = y * nx + x;
                        grid.items[fill[c] as usize] = k as u32;
                        fill[c] += 1;
                    }
                }
            }
        }
        grid
    }

    /// Whether the grid has no cells (the default grid).
    #[inline]
    pub(crate) fn is_empty(&self) -> bool {
        self.nx == 0
    }

    /// Side of a cell, metres.
    #[inline]
    pub(crate) fn cell_m(&self) -> f64 {
        self.cell_m
    }

    /// Number of cells along x and y.
    #[inline]
    pub(crate) fn size(&self) -> (usize, usize) {
        (self.nx, self.ny)
    }

    /// Cell coordinates of `p`, clamped to the grid (not empty).
    #[inline]
    pub(crate) fn clamped_cell(&self, p: DVec2) -> (usize, usize) {
        let q = (p - self.origin) / self.cell_m;
        let x = (q.x.floor().max(0.0) as usize).min(self.nx - 1);
        let y = (q.y.floor().max(0.0) as usize).min(self.ny - 1);
        (x, y)
    }

    /// The cell containing `p`, or `None` outside the grid.
    #[inline]
    pub(crate) fn cell_containing(&self, p: DVec2) -> Option<(usize, usize)> {
        let q = (p - self.origin) / self.cell_m;
        (q.x >= 0.0 && q.y >= 0.0 && q.x < self.nx as f64 && q.y < self.ny as f64)
            .then_some((q.x as usize, q.y as usize))
    }

    /// Cell coordinates of `p`, not clamped (for ring searches that may start outside the grid).
    #[inline]
    pub(crate) fn cell_coords(&self, p: DVec2) -> (i64, i64) {
        let q = ((p - self.origin) / self.cell_m).floor();
        (q.x as i64, q.y as i64)
    }

    /// The items of cell (`x`, `y`).
    #[inline]
    pub(crate) fn items_in(&self, x: usize, y: usize) -> &[u32] {
        self.items_in_row(y, x, x)
    }

    /// The items of cells `x0..=x1` of row `y`, cell by cell (an item in several of them appears once per cell).
    #[inline]
    pub(crate) fn items_in_row(&self, y: usize, x0: usize, x1: usize) -> &[u32] {
        let row = y * self.nx;
        &self.items[self.starts[row + x0] as usize..self.starts[row + x1 + 1] as usize]
    }

    /// Calls `f` with every item listed in the 3 × 3 cells around the cell of `p` (not empty).
    pub(crate) fn for_items_around(&self, p: DVec2, mut f: impl FnMut(usize)) {
        let (cx, cy) = self.clamped_cell(p);
        let (x0, x1) = (cx.saturating_sub(1), (cx + 1).min(self.nx - 1));
        for y in cy.saturating_sub(1)..=(cy + 1).min(self.ny - 1) {
            for &k in self.items_in_row(y, x0, x1) {
                f(k as usize);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn items_land_in_the_cells_of_their_boxes_in_index_order() {
        let boxes = [
            (DVec2::new(0.5, 0.5), DVec2::new(0.5, 0.5)),
            (DVec2::new(0.0, 0.0), DVec2::new(9.0, 3.0)),
            (DVec2::new(9.5, 9.5), DVec2::new(9.5, 9.5)),
            (DVec2::ZERO, DVec2::splat(10.0)), // left out
        ];
        let grid = CellGrid::build(DVec2::ZERO, DVec2::splat(10.0), 2.0, 1e6, boxes.len(), |k| {
            (k != 3).then_some(boxes[k])
        });
        assert_eq!(grid.size(), (6, 6));
        assert_eq!(grid.items_in(0, 0), &[0, 1]);
        assert_eq!(grid.items_in(4, 1), &[1]);
        assert_eq!(grid.items_in(4, 2), &[] as &[u32]);
        assert_eq!(grid.items_in(4, 4), &[2]);
        assert_eq!(grid.cell_containing(DVec2::new(-0.1, 1.0)), None);
        assert_eq!(grid.cell_containing(DVec2::new(9.9, 1.0)), Some((4, 0)));
        let mut around = Vec::new();
        grid.for_items_around(DVec2::new(7.0, 7.0), |k| around.push(k));
        assert_eq!(around, vec![2]);
        // Too many cells for the cap: the cells grow.
        let coarse = CellGrid::build(DVec2::ZERO, DVec2::splat(1000.0), 2.5, 100.0, 0, |_| None);
        assert!(coarse.cell_m() >= 100.0 && coarse.size().0 * coarse.size().1 <= 100);
    }
}
