//! The tolerance box of a scenario: every input between its tolerance limits
//! ([`rvtol_engine::scenario::ColumnInfo::tolerance`]), cut by the parts' 001 Eq. 11
//! constraints, as coordinates a worst-case search moves one at a time.
//!
//! A random column without a constraint is a coordinate of its own, with the two ends of
//! its interval as vertices and five levels for the search (the ends, the quarter points
//! and the centre). The two columns of one Eq. 11 inequality, c₀·x + c₁·y ≤ b, form one
//! coordinate: the feasible part of their rectangle is a convex polygon, whose corners
//! are its vertices (a linear function's extremes over it lie there), and whose levels
//! add its vertex mean and the midpoints from it to each corner (feasible by convexity).

use rvtol_deviation::LinearInequality;
use rvtol_engine::scenario::{Scenario, ScenarioError};

/// One coordinate of the box: the columns it moves and the points it may take.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct Coordinate {
    /// One column, or the two of an Eq. 11 inequality.
    pub columns: Vec<usize>,
    /// Its corners (in `columns` order).
    pub vertices: Vec<Vec<f64>>,
    /// The corners and the inner points the search also tries.
    pub levels: Vec<Vec<f64>>,
}

/// The box: its centre row and its coordinates.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct ToleranceBox {
    /// Every column at the centre of its tolerance interval.
    pub centre: Vec<f64>,
    /// Half the width of each column's interval (0 for a column that does not vary).
    pub half_width: Vec<f64>,
    /// The coordinates, in column order of their first column.
    pub coordinates: Vec<Coordinate>,
}

impl ToleranceBox {
    /// The box of `scenario`; an error when an Eq. 11 constraint leaves none of its
    /// rectangle or two inequalities share a column.
    pub fn of(scenario: &Scenario) -> Result<ToleranceBox, ScenarioError> {
        let space = &scenario.input_space;
        let limits: Vec<[f64; 2]> = (0..space.n_columns())
            .map(|c| match space.is_random(c) {
                true => scenario.columns[c].tolerance,
                false => {
                    let value = space.mean_row()[c];
                    [value, value]
                }
            })
            .collect();
        let centre: Vec<f64> = limits.iter().map(|[a, b]| 0.5 * (a + b)).collect();
        let half_width: Vec<f64> = limits.iter().map(|[a, b]| 0.5 * (b - a)).collect();
        let mut taken = vec![false; limits.len()];
        let mut coordinates = Vec::new();
        for (q, path) in space.inequalities().iter().zip(constraint_paths(scenario)) {
            if q.columns.iter().any(|&c| taken[c]) {
                return Err(ScenarioError::new(
                    path,
                    "the worst case needs each Eq. 11 inequality on columns of its own",
                ));
            }
            q.columns.iter().for_each(|&c| taken[c] = true);
            coordinates.push(polygon(q, &limits).ok_or_else(|| {
                ScenarioError::new(
                    path,
                    "no point of the part's tolerance box meets its Eq. 11 constraint",
                )
            })?);
        }
        for (c, &[low, high]) in limits.iter().enumerate() {
            if !taken[c] && high > low {
                coordinates.push(interval(c, low, high));
            }
        }
        coordinates.sort_by_key(|k| k.columns[0]);
        Ok(ToleranceBox {
            centre,
            half_width,
            coordinates,
        })
    }

    /// The number of corners of the box (the product over the coordinates), saturating.
    pub fn vertex_count(&self) -> u64 {
        (self.coordinates.iter()).fold(1u64, |n, k| n.saturating_mul(k.vertices.len() as u64))
    }

    /// The number of corners as a float (exact below 2⁵³).
    pub fn corners(&self) -> f64 {
        (self.coordinates.iter())
            .map(|k| k.vertices.len() as f64)
            .product()
    }

    /// Corner `index` of the box as a row (mixed radix over the coordinates' vertices).
    pub fn vertex(&self, mut index: u64, row: &mut [f64]) {
        for k in &self.coordinates {
            let n = k.vertices.len() as u64;
            k.set(row, &k.vertices[(index % n) as usize]);
            index /= n;
        }
    }
}

impl ToleranceBox {
    /// Whether every coordinate of `row` sits at one of its vertices.
    pub fn is_corner(&self, row: &[f64]) -> bool {
        (self.coordinates.iter()).all(|k| k.vertices.iter().any(|v| k.holds(row, v)))
    }
}

impl Coordinate {
    /// Puts `point` into `row`.
    pub fn set(&self, row: &mut [f64], point: &[f64]) {
        for (&c, &x) in self.columns.iter().zip(point) {
            row[c] = x;
        }
    }

    /// Whether `row` holds `point` in this coordinate's columns.
    pub fn holds(&self, row: &[f64], point: &[f64]) -> bool {
        self.columns.iter().zip(point).all(|(&c, &x)| row[c] == x)
    }

    /// The vertex with the largest Σ g_c·x_c (the first of equals).
    pub fn best_vertex(&self, gradient: &[f64]) -> &[f64] {
        let score = |v: &Vec<f64>| -> f64 {
            (self.columns.iter().zip(v))
                .map(|(&c, &x)| gradient[c] * x)
                .sum()
        };
        let mut best = &self.vertices[0];
        for v in &self.vertices[1..] {
            if score(v) > score(best) {
                best = v;
            }
        }
        best
    }
}

/// The JSON path of each inequality's part (two inequalities per constrained part).
fn constraint_paths(scenario: &Scenario) -> Vec<String> {
    (scenario.input_space.constraint_paths().iter())
        .flat_map(|p| std::iter::repeat_n(format!("{p}.tolerance_band"), 2))
        .collect()
}

/// A column's interval as a coordinate.
fn interval(column: usize, low: f64, high: f64) -> Coordinate {
    let at = |t: f64| vec![low + t * (high - low)];
    Coordinate {
        columns: vec![column],
        vertices: vec![vec![low], vec![high]],
        levels: vec![vec![low], at(0.25), at(0.5), at(0.75), vec![high]],
    }
}

/// The rectangle of the inequality's two columns cut by it, as a coordinate; `None`
/// when nothing of the rectangle meets it.
fn polygon(q: &LinearInequality, limits: &[[f64; 2]]) -> Option<Coordinate> {
    let [a, b] = q.columns.map(|c| limits[c]);
    let [ca, cb] = q.coefficients;
    let meets = |x: f64, y: f64| ca * x + cb * y <= q.bound * (1.0 + 1e-12) + 1e-300;
    let mut vertices: Vec<Vec<f64>> = Vec::new();
    let mut push = |x: f64, y: f64| {
        if meets(x, y) && !vertices.iter().any(|v| v[0] == x && v[1] == y) {
            vertices.push(vec![x, y]);
        }
    };
    for (x, y) in [(a[0], b[0]), (a[1], b[0]), (a[1], b[1]), (a[0], b[1])] {
        push(x, y);
    }
    // Where the line c_a·x + c_b·y = bound crosses the rectangle's edges.
    for x in a {
        let y = (q.bound - ca * x) / cb;
        if cb != 0.0 && y > b[0] && y < b[1] {
            push(x, y);
        }
    }
    for y in b {
        let x = (q.bound - cb * y) / ca;
        if ca != 0.0 && x > a[0] && x < a[1] {
            push(x, y);
        }
    }
    if vertices.is_empty() {
        return None;
    }
    let n = vertices.len() as f64;
    let inner: Vec<f64> = (0..2)
        .map(|i| vertices.iter().map(|v| v[i]).sum::<f64>() / n)
        .collect();
    let mut levels = vertices.clone();
    levels.push(inner.clone());
    for v in &vertices {
        levels.push(vec![0.5 * (v[0] + inner[0]), 0.5 * (v[1] + inner[1])]);
    }
    Some(Coordinate {
        columns: q.columns.to_vec(),
        vertices,
        levels,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_constraint_cuts_its_rectangle_to_a_polygon() {
        // x + y ≤ 1 on [0, 1]²: the triangle (0, 0), (1, 0), (0, 1).
        let q = LinearInequality {
            columns: [0, 1],
            coefficients: [1.0, 1.0],
            bound: 1.0,
        };
        let k = polygon(&q, &[[0.0, 1.0], [0.0, 1.0]]).unwrap();
        assert_eq!(
            k.vertices,
            vec![vec![0.0, 0.0], vec![1.0, 0.0], vec![0.0, 1.0]]
        );
        // x + 0.5·y ≤ 0.75 on [0, 1]²: the corners (0, 0) and (0, 1), and where the line
        // crosses y = 0 (x = 0.75) and y = 1 (x = 0.25).
        let q = LinearInequality {
            coefficients: [1.0, 0.5],
            bound: 0.75,
            ..q
        };
        let k = polygon(&q, &[[0.0, 1.0], [0.0, 1.0]]).unwrap();
        assert_eq!(
            k.vertices,
            vec![
                vec![0.0, 0.0],
                vec![0.0, 1.0],
                vec![0.75, 0.0],
                vec![0.25, 1.0]
            ]
        );
        let inner = &k.levels[4];
        assert!(q.coefficients[0] * inner[0] + q.coefficients[1] * inner[1] <= q.bound);
        // Nothing of [2, 3]² meets x + y ≤ 1.
        let q = LinearInequality {
            coefficients: [1.0, 1.0],
            bound: 1.0,
            ..q
        };
        assert!(polygon(&q, &[[2.0, 3.0], [2.0, 3.0]]).is_none());
    }

    #[test]
    fn vertices_are_numbered_in_mixed_radix() {
        let b = ToleranceBox {
            centre: vec![0.0; 2],
            half_width: vec![1.0; 2],
            coordinates: vec![interval(0, -1.0, 1.0), interval(1, 5.0, 7.0)],
        };
        assert_eq!(b.vertex_count(), 4);
        let mut row = vec![0.0; 2];
        let corners: Vec<Vec<f64>> = (0..4)
            .map(|i| {
                b.vertex(i, &mut row);
                row.clone()
            })
            .collect();
        assert_eq!(
            corners,
            vec![
                vec![-1.0, 5.0],
                vec![1.0, 5.0],
                vec![-1.0, 7.0],
                vec![1.0, 7.0]
            ]
        );
        assert_eq!(b.coordinates[0].best_vertex(&[-2.0, 0.0]), &[-1.0]);
    }
}
