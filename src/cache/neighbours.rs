//! Křivánek's neighbour clamping (Křivánek et al. 2006, "Making radiance and irradiance
//! caching practical: adaptive caching and neighbor clamping"; as Mitsuba 0.6 does it): a
//! radius stands for the distance to the nearest geometry, which can differ between two
//! records by no more than the distance between them, so a new record's radius (before the
//! pixel and scene clamps) is cut to `R_j + ‖x_i − x_j‖` of each record j within it, and each
//! such record's to `R_i + ‖x_i − x_j‖`, its clamps then applied again. Records are clamped
//! one at a time in the order they are made, so the radii do not depend on threads.

use std::collections::HashMap;

use glam::Vec3;

use super::records::Record;

/// The records' points in a uniform grid, and each record's radius before the clamps.
pub(crate) struct Neighbours {
    cell: f32,
    grid: HashMap<[i32; 3], Vec<u32>>,
    /// Per record (by id): its radius before the pixel and scene clamps.
    unclamped: Vec<f32>,
}

impl Neighbours {
    /// None yet; the grid's cells of side `cell`.
    pub fn new(cell: f32) -> Self {
        Neighbours {
            cell,
            grid: HashMap::new(),
            unclamped: vec![],
        }
    }

    fn cell_of(&self, p: Vec3) -> [i32; 3] {
        (p / self.cell).floor().to_array().map(|c| c as i32)
    }

    /// The records closer to `point` than `radius`, in id order.
    fn within(&self, records: &[Record], point: Vec3, radius: f32) -> Vec<u32> {
        let lo = self.cell_of(point - Vec3::splat(radius));
        let hi = self.cell_of(point + Vec3::splat(radius));
        let cells: f64 = (0..3).map(|a| hi[a] as f64 - lo[a] as f64 + 1.0).product();
        let near = |id: &u32| (records[*id as usize].point - point).length() < radius;
        let mut found: Vec<u32> = if !radius.is_finite() || cells > records.len() as f64 {
            (0..records.len() as u32).filter(near).collect()
        } else {
            let mut found = vec![];
            for x in lo[0]..=hi[0] {
                for y in lo[1]..=hi[1] {
                    for z in lo[2]..=hi[2] {
                        found.extend(
                            self.grid
                                .get(&[x, y, z])
                                .into_iter()
                                .flatten()
                                .filter(|id| near(id)),
                        );
                    }
                }
            }
            found
        };
        found.sort_unstable();
        found
    }

    /// The radius (before the clamps) of a new record at `point` whose own is `unclamped`,
    /// cut by its neighbours'; the neighbours' radii cut by it, in `records`, `clamp` giving a
    /// record's radius from its unclamped one (the pixel and scene clamps at its pixel).
    pub fn clamp(
        &mut self,
        records: &mut [Record],
        point: Vec3,
        unclamped: f32,
        clamp: impl Fn(u32, f32) -> f32,
    ) -> f32 {
        let near = self.within(records, point, unclamped);
        let distance = |records: &[Record], id: u32| (records[id as usize].point - point).length();
        let mut own = unclamped;
        for &id in &near {
            own = own.min(self.unclamped[id as usize] + distance(records, id));
        }
        for &id in &near {
            let limit = own + distance(records, id);
            if self.unclamped[id as usize] > limit {
                self.unclamped[id as usize] = limit;
                let record = &mut records[id as usize];
                record.radius = clamp(record.pixel, limit);
            }
        }
        own
    }

    /// Adds the next record (ids in the order made), at `point`, of radius `unclamped`.
    pub fn insert(&mut self, point: Vec3, unclamped: f32) {
        let id = self.unclamped.len() as u32;
        self.unclamped.push(unclamped);
        let cell = self.cell_of(point);
        self.grid.entry(cell).or_default().push(id);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn record(pixel: u32, x: f32, radius: f32) -> Record {
        Record {
            pixel,
            point: Vec3::new(x, 0.0, 0.0),
            normal: Vec3::Z,
            e: 1.0,
            radius,
            level: 0,
            gradients: None,
        }
    }

    #[test]
    fn a_radius_differs_from_a_neighbours_by_at_most_their_distance() {
        // Records at x = 0 (R 0.5) and x = 10 (R 100); a new one at x = 1 with R 50 is cut to
        // 0.5 + 1 = 1.5, and cuts the far one to 1.5 + 9 = 10.5 (its clamp: at most 8).
        let mut neighbours = Neighbours::new(0.25);
        let mut records = vec![record(0, 0.0, 0.5), record(1, 10.0, 8.0)];
        neighbours.insert(records[0].point, 0.5);
        neighbours.insert(records[1].point, 100.0);
        let clamp = |_, r: f32| r.min(8.0);
        let own = neighbours.clamp(&mut records, Vec3::X, 50.0, clamp);
        assert_eq!(own, 1.5);
        assert_eq!(neighbours.unclamped[1], 10.5);
        assert_eq!(records[1].radius, 8.0);
        assert_eq!(records[0].radius, 0.5, "no larger than 1.5 + 1: untouched");
        // A small new radius reaches no record: nothing changes.
        let own = neighbours.clamp(&mut records, Vec3::new(5.0, 0.0, 0.0), 0.1, clamp);
        assert_eq!((own, neighbours.unclamped[1]), (0.1, 10.5));
    }

    #[test]
    fn the_grid_finds_what_a_scan_finds() {
        let mut neighbours = Neighbours::new(0.5);
        let records: Vec<Record> = (0..300)
            .map(|i| record(i, (i as f32 * 0.731).sin() * 20.0, 1.0))
            .collect();
        for r in &records {
            neighbours.insert(r.point, 1.0);
        }
        for k in 0..100 {
            let point = Vec3::new(-21.0 + 0.42 * k as f32, 0.0, 0.0);
            for radius in [0.3, 2.0, 15.0, f32::INFINITY] {
                let scan: Vec<u32> = (0..300u32)
                    .filter(|&i| (records[i as usize].point - point).length() < radius)
                    .collect();
                assert_eq!(
                    neighbours.within(&records, point, radius),
                    scan,
                    "{point} {radius}"
                );
            }
        }
    }
}
