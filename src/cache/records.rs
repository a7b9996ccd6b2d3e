//! An irradiance cache's records, Ward's weight, and the grids that find the records covering a
//! point.

use std::collections::HashMap;

use glam::Vec3;

use super::gradients::Gradients;

/// One record: the irradiance at a pixel's surface point and the radius it holds for.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Record {
    /// The pixel (row-major index) whose surface point it is.
    pub pixel: u32,
    /// The point x_i.
    pub point: Vec3,
    /// Its normal n_i, facing the camera.
    pub normal: Vec3,
    /// Its irradiance E_i.
    pub e: f32,
    /// Its radius R_i.
    pub radius: f32,
    /// The placement level it was made at (0: every pixel; k: every 2^k-th).
    pub level: u32,
    /// Its gradients, where the cache takes them (`--gradients`).
    pub gradients: Option<Gradients>,
}

impl Record {
    /// Ward's ε_i at `point` with `normal`: `‖x − x_i‖ / R_i + √(1 − n·n_i)`. A point uses the
    /// record where ε_i < a, with weight 1/ε_i. The record's own pixel has ε = 0.
    pub fn error(&self, pixel: u32, point: Vec3, normal: Vec3) -> f32 {
        if pixel == self.pixel {
            return 0.0;
        }
        let distance = (point - self.point).length();
        let spatial = if distance == 0.0 {
            0.0
        } else {
            distance / self.radius
        };
        spatial + (1.0 - normal.dot(self.normal)).max(0.0).sqrt()
    }

    /// Its E carried to `point` with `normal`: E_i, or, with gradients, `E_i + (n_i × n)·∇_r
    /// + (x − x_i)·∇_t`, at least 0.
    pub fn e_at(&self, point: Vec3, normal: Vec3) -> f64 {
        match &self.gradients {
            None => self.e as f64,
            Some(g) => {
                let turn = self.normal.cross(normal).dot(g.rotation) as f64;
                let shift = (point - self.point).dot(g.translation) as f64;
                (self.e as f64 + turn + shift).max(0.0)
            }
        }
    }
}

/// Cell sides double from one grid to the next: a record goes to the first grid whose cells
/// are at least its reach, so its sphere overlaps at most 2 × 2 × 2 of them.
const GRIDS: usize = 48;

/// The records in a stack of uniform grids, cells of side `cell · 2^k` in grid k: each record
/// in the cells of its grid that its sphere of influence (radius `a · R_i`, outside which
/// ε_i ≥ a) overlaps, and a record that reaches everywhere (R_i = +inf) in a list every query
/// reads. A query reads one cell per grid; lookups are in record order, so sums over them do
/// not depend on threads.
pub(crate) struct RecordIndex {
    accuracy: f32,
    cell: f32,
    grids: Vec<HashMap<[i32; 3], Vec<u32>>>,
    everywhere: Vec<u32>,
}

impl RecordIndex {
    /// An empty index for accuracy `a`, with cells of side `cell` in its finest grid.
    pub fn new(accuracy: f32, cell: f32) -> Self {
        RecordIndex {
            accuracy,
            cell,
            grids: vec![],
            everywhere: vec![],
        }
    }

    fn cell_of(&self, grid: usize, p: Vec3) -> [i32; 3] {
        // `as` saturates: a point far outside the scene lands in an edge cell.
        (p / (self.cell * (1u64 << grid) as f32))
            .floor()
            .to_array()
            .map(|c| c as i32)
    }

    /// Adds record `id` (its ids must grow with each insert).
    pub fn insert(&mut self, id: u32, record: &Record) {
        let reach = self.accuracy * record.radius;
        let grid = (0..GRIDS).find(|&k| self.cell * (1u64 << k) as f32 >= reach);
        let Some(grid) = grid.filter(|_| reach.is_finite()) else {
            self.everywhere.push(id);
            return;
        };
        if self.grids.len() <= grid {
            self.grids.resize_with(grid + 1, HashMap::new);
        }
        let lo = self.cell_of(grid, record.point - Vec3::splat(reach));
        let hi = self.cell_of(grid, record.point + Vec3::splat(reach));
        for x in lo[0]..=hi[0] {
            for y in lo[1]..=hi[1] {
                for z in lo[2]..=hi[2] {
                    self.grids[grid].entry([x, y, z]).or_default().push(id);
                }
            }
        }
    }

    /// The records that may cover `point`: one cell of each grid, then the list.
    fn near(&self, point: Vec3) -> impl Iterator<Item = u32> + '_ {
        let cells = self
            .grids
            .iter()
            .enumerate()
            .filter_map(move |(k, grid)| grid.get(&self.cell_of(k, point)));
        cells.flatten().chain(&self.everywhere).copied()
    }

    /// The records pixel `pixel`'s point uses (ε < a), as (id, ε) in id order, into `out`.
    pub fn covering(
        &self,
        records: &[Record],
        pixel: u32,
        point: Vec3,
        normal: Vec3,
        out: &mut Vec<(u32, f32)>,
    ) {
        out.clear();
        for id in self.near(point) {
            let error = records[id as usize].error(pixel, point, normal);
            if error < self.accuracy {
                out.push((id, error));
            }
        }
        out.sort_unstable_by_key(|&(id, _)| id);
    }

    /// Whether any record covers pixel `pixel`'s point.
    pub fn covers(&self, records: &[Record], pixel: u32, point: Vec3, normal: Vec3) -> bool {
        self.near(point)
            .any(|id| records[id as usize].error(pixel, point, normal) < self.accuracy)
    }
}

/// E at `point` with `normal` from the records covering it (`covering`, as
/// [`RecordIndex::covering`] gives them): the record at the point itself where there is one
/// (ε = 0), else `Σ w_i E_i / Σ w_i` with `w_i = 1/ε_i` (each E_i carried to the point by its
/// gradients where it has them, [`Record::e_at`]). NaN where none covers it.
pub fn interpolate(records: &[Record], covering: &[(u32, f32)], point: Vec3, normal: Vec3) -> f32 {
    if let Some(&(id, _)) = covering.iter().find(|(_, error)| *error == 0.0) {
        return records[id as usize].e;
    }
    let (mut sum, mut weights) = (0.0f64, 0.0f64);
    for &(id, error) in covering {
        let w = 1.0 / error as f64;
        sum += w * records[id as usize].e_at(point, normal);
        weights += w;
    }
    (sum / weights) as f32
}

#[cfg(test)]
mod tests {
    use super::*;

    fn record(pixel: u32, x: f32, e: f32, radius: f32) -> Record {
        Record {
            pixel,
            point: Vec3::new(x, 0.0, 0.0),
            normal: Vec3::Z,
            e,
            radius,
            level: 0,
            gradients: None,
        }
    }

    #[test]
    fn wards_weight_by_distance_and_normal() {
        let r = record(0, 0.0, 1.0, 2.0);
        assert_eq!(
            r.error(0, Vec3::new(5.0, 0.0, 0.0), -Vec3::Z),
            0.0,
            "its own pixel"
        );
        assert_eq!(r.error(1, Vec3::new(1.0, 0.0, 0.0), Vec3::Z), 0.5);
        let tilted = Vec3::new(0.6, 0.0, 0.8);
        let expected = (1.0f32 - 0.8).sqrt();
        assert!((r.error(1, Vec3::ZERO, tilted) - expected).abs() < 1e-6);
    }

    #[test]
    fn the_index_finds_exactly_the_records_a_scan_finds() {
        let records: Vec<Record> = (0..200)
            .map(|i| {
                let x = (i as f32 * 0.37).sin() * 10.0;
                let radius = if i % 50 == 0 {
                    f32::INFINITY
                } else {
                    0.5 + (i % 7) as f32
                };
                record(i, x, i as f32, radius)
            })
            .collect();
        let a = 0.3;
        let mut index = RecordIndex::new(a, 0.25);
        for (id, r) in records.iter().enumerate() {
            index.insert(id as u32, r);
        }
        let mut found = vec![];
        for k in 0..400 {
            let point = Vec3::new(-12.0 + k as f32 * 0.06, 0.01 * k as f32, 0.0);
            index.covering(&records, 1000, point, Vec3::Z, &mut found);
            let scan: Vec<(u32, f32)> = records
                .iter()
                .enumerate()
                .map(|(id, r)| (id as u32, r.error(1000, point, Vec3::Z)))
                .filter(|&(_, e)| e < a)
                .collect();
            assert_eq!(found, scan, "at {point}");
            assert_eq!(index.covers(&records, 1000, point, Vec3::Z), !scan.is_empty());
        }
    }

    #[test]
    fn interpolation_weights_by_the_inverse_error_and_takes_an_exact_record() {
        let records = [record(0, 0.0, 1.0, 1.0), record(1, 1.0, 4.0, 1.0)];
        // ε 0.25 and 0.75: weights 4 and 4/3.
        let at = |covering: &[(u32, f32)]| interpolate(&records, covering, Vec3::X, Vec3::Z);
        let e = at(&[(0, 0.25), (1, 0.75)]);
        assert!((e - (4.0 * 1.0 + 4.0 / 3.0 * 4.0) / (4.0 + 4.0 / 3.0)).abs() < 1e-6);
        assert_eq!(at(&[(0, 0.25), (1, 0.0)]), 4.0);
        assert!(at(&[]).is_nan());
    }

    #[test]
    fn gradients_carry_a_records_e_to_the_point_and_never_below_zero() {
        let mut r = record(0, 0.0, 1.0, 1.0);
        r.gradients = Some(Gradients {
            rotation: Vec3::new(0.0, 2.0, 0.0),
            translation: Vec3::new(0.5, 0.0, 0.0),
        });
        // Moved 0.4 along x: + 0.2. Turned towards x by a small angle: n_i × n = (0, s, 0),
        // so + 2 s.
        assert!((r.e_at(Vec3::new(0.4, 0.0, 0.0), Vec3::Z) - 1.2).abs() < 1e-6);
        let n = Vec3::new(0.1, 0.0, 1.0).normalize();
        let expected = 1.0 + 2.0 * Vec3::Z.cross(n).y as f64;
        assert!((r.e_at(Vec3::ZERO, n) - expected).abs() < 1e-6);
        assert_eq!(r.e_at(Vec3::new(-4.0, 0.0, 0.0), Vec3::Z), 0.0);
        r.gradients = None;
        assert_eq!(r.e_at(Vec3::new(0.4, 0.0, 0.0), n), 1.0);
    }
}
