//! The one place where nalgebra (this project's public math) meets Rapier's glam math.

use nalgebra::{Isometry3, Point3, Quaternion, Translation3, UnitQuaternion, Vector3};
use rapier3d::math::{Pose, Rotation, Vector};

/// A nalgebra point or vector as Rapier's vector (f32).
pub(crate) fn to_vector(v: &Vector3<f64>) -> Vector {
    Vector::new(v.x as f32, v.y as f32, v.z as f32)
}

/// A point as Rapier's vector.
pub(crate) fn point_to_vector(p: &Point3<f64>) -> Vector {
    to_vector(&p.coords)
}

/// Rapier's vector as a nalgebra point.
pub(crate) fn to_point(v: Vector) -> Point3<f64> {
    Point3::new(f64::from(v.x), f64::from(v.y), f64::from(v.z))
}

/// A rotation as Rapier's quaternion.
pub(crate) fn to_rotation(q: &UnitQuaternion<f64>) -> Rotation {
    Rotation::from_xyzw(q.i as f32, q.j as f32, q.k as f32, q.w as f32).normalize()
}

/// An isometry as Rapier's pose.
pub(crate) fn to_pose(iso: &Isometry3<f64>) -> Pose {
    Pose::from_parts(to_vector(&iso.translation.vector), to_rotation(&iso.rotation))
}

/// Rapier's pose as an isometry.
pub(crate) fn from_pose(pose: &Pose) -> Isometry3<f64> {
    let q = pose.rotation;
    Isometry3::from_parts(
        Translation3::from(to_point(pose.translation).coords),
        UnitQuaternion::from_quaternion(Quaternion::new(
            f64::from(q.w),
            f64::from(q.x),
            f64::from(q.y),
            f64::from(q.z),
        )),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn poses_round_trip() {
        let iso = Isometry3::from_parts(
            Translation3::new(1.0, -2.0, 0.5),
            UnitQuaternion::from_euler_angles(0.1, -0.2, 1.3),
        );
        let back = from_pose(&to_pose(&iso));
        assert!((back.translation.vector - iso.translation.vector).norm() < 1e-6);
        assert!(back.rotation.angle_to(&iso.rotation) < 1e-6);
        // The same point transformed both ways.
        let p = Point3::new(0.3, 0.4, -0.2);
        let a = iso * p;
        let b = to_point(to_pose(&iso).transform_point(point_to_vector(&p)));
        assert!((a - b).norm() < 1e-6, "{a} vs {b}");
    }
}
