//! The camera's optics: the field of view at a zoom ratio, image points to directions and
//! back (a pinhole camera).

use super::*;

/// The camera's field of view at `zoom_ratio`, (horizontal, vertical) degrees.
///
/// Zooming divides the tangent of the half angle: hfov = 2·atan(tan(30°)/zoom), so 60° at
/// 1×, 32.2° at 2×; the vertical half angle's tangent is the horizontal one's × 9/16. A
/// ratio below 1 (or NaN) is taken as 1.
pub fn field_of_view_deg(zoom_ratio: f32) -> (f32, f32) {
    let (tx, ty) = half_fov_tangents(zoom_ratio);
    (
        2.0 * libm::atanf(tx).to_degrees(),
        2.0 * libm::atanf(ty).to_degrees(),
    )
}

/// How far past the image edge (in half widths) a target may be before it counts as out of
/// the image: absorbs the rounding of the angle round trip for a box on the edge.
pub(super) const EDGE_MARGIN: f32 = 1e-3;

/// Tangents of the camera's half angles (horizontal, vertical) at `zoom_ratio`.
pub(super) fn half_fov_tangents(zoom_ratio: f32) -> (f32, f32) {
    let zoom = if zoom_ratio > ZOOM_MIN {
        zoom_ratio
    } else {
        ZOOM_MIN
    };
    let tx = libm::tanf((CAMERA_HFOV_DEG / 2.0).to_radians()) / zoom;
    (tx, tx / CAMERA_ASPECT)
}

/// The direction of an image point from the camera's axis, (yaw, pitch) degrees: positive
/// right and up. A pinhole camera, each axis on its own.
pub(super) fn angular_offset(p: ImagePoint, zoom_ratio: f32) -> (f32, f32) {
    let (tx, ty) = half_fov_tangents(zoom_ratio);
    let nx = (f32::from(p.x()) - IMAGE_CENTRE) / IMAGE_CENTRE;
    let ny = (f32::from(p.y()) - IMAGE_CENTRE) / IMAGE_CENTRE;
    // Image y grows downwards, pitch upwards.
    (
        libm::atanf(nx * tx).to_degrees(),
        -libm::atanf(ny * ty).to_degrees(),
    )
}

/// Where a direction (yaw, pitch) degrees from the camera's axis is in the image, or
/// `None` when outside it: the inverse of [`angular_offset`], rounded and kept in
/// [0, 8191].
pub(super) fn image_point((yaw, pitch): (f32, f32), zoom_ratio: f32) -> Option<ImagePoint> {
    // At or beyond 90° the tangent no longer says the side: out of any image.
    if !(libm::fabsf(yaw) < 90.0 && libm::fabsf(pitch) < 90.0) {
        return None;
    }
    let (tx, ty) = half_fov_tangents(zoom_ratio);
    let nx = libm::tanf(yaw.to_radians()) / tx;
    let ny = -libm::tanf(pitch.to_radians()) / ty;
    let limit = 1.0 + EDGE_MARGIN;
    if !(libm::fabsf(nx) <= limit && libm::fabsf(ny) <= limit) {
        return None;
    }
    let max = f32::from(ImagePoint::MAX);
    let coordinate = |n: f32| libm::roundf(IMAGE_CENTRE + n * IMAGE_CENTRE).clamp(0.0, max) as i32;
    ImagePoint::new(coordinate(nx), coordinate(ny)).ok()
}
