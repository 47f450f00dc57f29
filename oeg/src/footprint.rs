//! The robot's footprint: the rectangle, in the base frame, that bounds everything the robot carries (nav2's
//! polygon `footprint`, here a rectangle). Turned with the robot's heading, it says which cells the robot
//! covers and how close it comes to a cell: the checks of a driven or planned path use it, never a disc.

use crate::geometry::{CellIndex, GridGeometry, GridWindow};

/// A rectangle in the robot's base frame (x forward, y left), metres.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Footprint {
    /// Rearmost x, metres.
    pub min_x_m: f64,
    /// Foremost x, metres.
    pub max_x_m: f64,
    /// Rightmost y, metres.
    pub min_y_m: f64,
    /// Leftmost y, metres.
    pub max_y_m: f64,
}

/// A planar pose: position, metres, and heading from +x, radians.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pose2 {
    /// World x, metres.
    pub x_m: f64,
    /// World y, metres.
    pub y_m: f64,
    /// Heading from +x, radians.
    pub yaw_rad: f64,
}

type Point = (f64, f64);

impl Footprint {
    /// Length along x, metres.
    pub fn length_m(&self) -> f64 {
        self.max_x_m - self.min_x_m
    }

    /// Width along y, metres.
    pub fn width_m(&self) -> f64 {
        self.max_y_m - self.min_y_m
    }

    /// The radius of the smallest circle about the base frame's origin that holds the footprint, metres
    /// (nav2's circumscribed radius: an inflation smaller than it lets a turning robot's corners reach an
    /// obstacle).
    pub fn circumscribed_radius_m(&self) -> f64 {
        let far = |a: f64, b: f64| a.abs().max(b.abs());
        far(self.min_x_m, self.max_x_m).hypot(far(self.min_y_m, self.max_y_m))
    }

    /// The corners in the world at `pose`, counter-clockwise from the rear right.
    pub fn corners(&self, pose: Pose2) -> [Point; 4] {
        let (s, c) = pose.yaw_rad.sin_cos();
        [
            (self.min_x_m, self.min_y_m),
            (self.max_x_m, self.min_y_m),
            (self.max_x_m, self.max_y_m),
            (self.min_x_m, self.max_y_m),
        ]
        .map(|(x, y)| (pose.x_m + c * x - s * y, pose.y_m + s * x + c * y))
    }

    /// The world rectangle that bounds the footprint at `pose`: its lowest and highest x and y, metres.
    pub fn bounds(&self, pose: Pose2) -> ((f64, f64), (f64, f64)) {
        let corners = self.corners(pose);
        let (lo_x, hi_x) = span(corners.iter().map(|p| p.0));
        let (lo_y, hi_y) = span(corners.iter().map(|p| p.1));
        ((lo_x, lo_y), (hi_x, hi_y))
    }

    /// The cells of `window` whose square overlaps the footprint at `pose` (touching edges do not count),
    /// in row-major order.
    pub fn cells_under(&self, window: &GridWindow, pose: Pose2) -> Vec<CellIndex> {
        let (geometry, region) = (window.geometry(), window.region());
        let corners = self.corners(pose);
        let ((lo_x, lo_y), (hi_x, hi_y)) = self.bounds(pose);
        let (Some(a), Some(b)) = (geometry.cell_of(lo_x, lo_y), geometry.cell_of(hi_x, hi_y)) else {
            return Vec::new();
        };
        let (rlo, rhi) = (region.min, region.max());
        let mut cells = Vec::new();
        for j in a.j.max(rlo.j)..=b.j.min(rhi.j) {
            for i in a.i.max(rlo.i)..=b.i.min(rhi.i) {
                let cell = CellIndex::new(i, j);
                if polygons_overlap(&corners, &cell_square(geometry, cell)) {
                    cells.push(cell);
                }
            }
        }
        cells
    }

    /// The distance from the footprint at `pose` to the square of `cell`, metres (0 when they overlap).
    pub fn distance_to_cell(&self, geometry: &GridGeometry, cell: CellIndex, pose: Pose2) -> f64 {
        let a = self.corners(pose);
        let b = cell_square(geometry, cell);
        if polygons_overlap(&a, &b) {
            return 0.0;
        }
        let mut best = f64::INFINITY;
        for (p, poly) in a.iter().map(|p| (p, &b)).chain(b.iter().map(|p| (p, &a))) {
            for k in 0..4 {
                best = best.min(point_segment_distance(*p, poly[k], poly[(k + 1) % 4]));
            }
        }
        best
    }
}

fn span(values: impl Iterator<Item = f64>) -> (f64, f64) {
    values.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
        (lo.min(v), hi.max(v))
    })
}

fn cell_square(geometry: &GridGeometry, cell: CellIndex) -> [Point; 4] {
    let (x0, y0) = geometry.cell_min_corner(cell);
    let r = geometry.resolution_m();
    [(x0, y0), (x0 + r, y0), (x0 + r, y0 + r), (x0, y0 + r)]
}

/// Whether two convex quadrilaterals overlap with a positive area (separating axis theorem; a gap of a
/// nanometre or touching edges separate them).
fn polygons_overlap(a: &[Point; 4], b: &[Point; 4]) -> bool {
    for poly in [a, b] {
        for k in 0..4 {
            let (p, q) = (poly[k], poly[(k + 1) % 4]);
            let axis = (q.1 - p.1, p.0 - q.0);
            let project = |s: &[Point; 4]| span(s.iter().map(|v| v.0 * axis.0 + v.1 * axis.1));
            let ((a0, a1), (b0, b1)) = (project(a), project(b));
            let tolerance = 1e-9 * (axis.0.abs() + axis.1.abs());
            if a1 <= b0 + tolerance || b1 <= a0 + tolerance {
                return false;
            }
        }
    }
    true
}

fn point_segment_distance(p: Point, a: Point, b: Point) -> f64 {
    let (dx, dy) = (b.0 - a.0, b.1 - a.1);
    let len2 = dx * dx + dy * dy;
    let t = if len2 > 0.0 {
        (((p.0 - a.0) * dx + (p.1 - a.1) * dy) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (p.0 - a.0 - t * dx).hypot(p.1 - a.1 - t * dy)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::CellRegion;

    fn pioneer_like() -> Footprint {
        Footprint {
            min_x_m: -0.25,
            max_x_m: 0.25,
            min_y_m: -0.25,
            max_y_m: 0.25,
        }
    }

    #[test]
    fn the_rectangle_covers_the_cells_it_overlaps_and_turns_with_the_heading() {
        let g = GridGeometry::new(0.1).expect("geometry");
        let region =
            CellRegion::from_corners(CellIndex::new(-20, -20), CellIndex::new(20, 20)).expect("region");
        let f = Footprint {
            min_x_m: -0.2,
            max_x_m: 0.2,
            min_y_m: -0.05,
            max_y_m: 0.05,
        };
        // Heading +x at a cell corner: 4 x 1 cells on each side of the x axis.
        let along_x = f.cells_under(
            &GridWindow::new(g, region),
            Pose2 {
                x_m: 0.0,
                y_m: 0.0,
                yaw_rad: 0.0,
            },
        );
        assert_eq!(along_x.len(), 8, "{along_x:?}");
        assert!(
            along_x
                .iter()
                .all(|c| (-2..2).contains(&c.i) && (-1..1).contains(&c.j))
        );
        // Turned a quarter: the same cells transposed.
        let along_y = f.cells_under(
            &GridWindow::new(g, region),
            Pose2 {
                x_m: 0.0,
                y_m: 0.0,
                yaw_rad: std::f64::consts::FRAC_PI_2,
            },
        );
        assert_eq!(along_y.len(), 8);
        assert!(
            along_y
                .iter()
                .all(|c| (-1..1).contains(&c.i) && (-2..2).contains(&c.j))
        );
        // Turned 45 degrees: a diagonal band, and never the far corners of its bounding box.
        let diagonal = f.cells_under(
            &GridWindow::new(g, region),
            Pose2 {
                x_m: 0.0,
                y_m: 0.0,
                yaw_rad: std::f64::consts::FRAC_PI_4,
            },
        );
        assert!(diagonal.contains(&CellIndex::new(1, 1)) && diagonal.contains(&CellIndex::new(-2, -2)));
        assert!(!diagonal.contains(&CellIndex::new(1, -2)) && !diagonal.contains(&CellIndex::new(-2, 1)));
    }

    #[test]
    fn the_distance_to_a_cell_is_the_gap_between_the_shapes() {
        let g = GridGeometry::new(0.1).expect("geometry");
        let f = pioneer_like();
        let at = Pose2 {
            x_m: 0.0,
            y_m: 0.0,
            yaw_rad: 0.0,
        };
        // The cell from x = 0.5 to 0.6: 0.25 m beyond the front edge.
        assert!((f.distance_to_cell(&g, CellIndex::new(5, 0), at) - 0.25).abs() < 1e-12);
        assert_eq!(f.distance_to_cell(&g, CellIndex::new(0, 0), at), 0.0);
        // Turned 45 degrees, the front corner reaches 0.354 m along x.
        let turned = Pose2 {
            yaw_rad: std::f64::consts::FRAC_PI_4,
            ..at
        };
        let d = f.distance_to_cell(&g, CellIndex::new(5, -1), turned);
        assert!((d - (0.5 - 0.25 * 2f64.sqrt())).abs() < 1e-9, "{d}");
    }
}
