//! The camera definition files (MAVLink camera definition XML, the `mavlinkcamera` schema
//! QGroundControl and MAVSDK parse), kept in flash and served read-only over MAVLink FTP
//! ([`crate::ftp`]) as `camera.xml`, announced in `CAMERA_INFORMATION.cam_definition_uri` as
//! `mftp://camera.xml`.
//!
//! That URI form is the one both clients read alike: MAVSDK strips `mftp://` and opens the
//! rest (`camera.xml`), and loads the file from where its FTP client stored it only when
//! the path has no directory (`camera_impl.cpp`:1429-1477, at mavlink/MAVSDK 158e339);
//! QGroundControl keeps one `/` (`/camera.xml`, `FTPManager.cc`:1181-1212, at
//! HTRamsey/qgroundcontrol c15cc32). The FTP server takes a path with or without its
//! leading `/`.
//!
//! Both clients cache a definition by vendor, model and `cam_definition_version`
//! (`VehicleCameraControl.cc`:105-111; `camera_impl.cpp`:1321-1333), so the version is
//! raised with every change of a file (`tests/mavlink_camera.py` checks [`VERSION`] against
//! the files' `<definition version>`).
//!
//! The files hold an empty `<model>`, which the file served fills with
//! `CAMERA_INFORMATION`'s model name (`file`): QGroundControl 5.0 renames the camera to
//! the definition's model once it has loaded it (`VehicleCameraControl.cc` `_loadConstants`,
//! :835-848 at a11717e), and then no longer finds the name it listed the camera under when
//! the camera goes away (`QGCCameraManager.cc`:217, 274), so a stale entry stayed in its
//! camera list while the two differed.
//!
//! The files' parameters are [`settings::PARAMETERS`](super::settings::PARAMETERS): every
//! camera has focus (QGroundControl has no focus control but the definition's settings),
//! a camera with a thermal sensor has its palette and electronic zoom too.

use crate::ftp::File;

/// `cam_definition_version`, as in both files.
pub const VERSION: u16 = 2;
/// `cam_definition_uri`.
pub const URI: &str = "mftp://camera.xml";
/// The path the file is served at.
pub const PATH: &str = "/camera.xml";

/// The zoom camera's definition (every family but the dual light).
pub const ZOOM: &[u8] = include_bytes!("../../camera-definitions/idu-zoom.xml");
/// The dual-light camera's definition.
pub const DUAL_LIGHT: &[u8] = include_bytes!("../../camera-definitions/idu-dual-light.xml");

/// Whether `s` starts with `prefix` (`<[u8]>::starts_with` is not `const`).
const fn starts_with(mut s: &[u8], mut prefix: &[u8]) -> bool {
    loop {
        match (prefix.split_first(), s.split_first()) {
            (None, _) => return true,
            (Some((a, p)), Some((b, r))) if *a == *b => (prefix, s) = (p, r),
            _ => return false,
        }
    }
}

/// Where the model's name goes in `xml`: just after its `<model>`; 0 when it has none.
const fn model_at(xml: &[u8]) -> usize {
    const TAG: &[u8] = b"<model>";
    let (mut rest, mut at) = (xml, 0usize);
    loop {
        if starts_with(rest, TAG) {
            return at.saturating_add(TAG.len());
        }
        match rest.split_first() {
            Some((_, r)) => (rest, at) = (r, at.saturating_add(1)),
            None => return 0,
        }
    }
}

/// A definition split where its model's name goes.
const fn split(xml: &'static [u8]) -> (&'static [u8], &'static [u8]) {
    match xml.split_at_checked(model_at(xml)) {
        Some(parts) => parts,
        None => (xml, &[]),
    }
}

static ZOOM_PARTS: (&[u8], &[u8]) = split(ZOOM);
static DUAL_LIGHT_PARTS: (&[u8], &[u8]) = split(DUAL_LIGHT);
// Both files have a `<model>` to fill: a file without one fails the build.
const _: () = assert!(model_at(ZOOM) > 0 && model_at(DUAL_LIGHT) > 0);

/// The definition served for a camera with or without a thermal sensor, its `<model>` filled
/// with `model` (`CAMERA_INFORMATION`'s).
pub(crate) fn file(thermal: bool, model: &'static str) -> File<'static> {
    let (head, tail) = if thermal {
        DUAL_LIGHT_PARTS
    } else {
        ZOOM_PARTS
    };
    File {
        path: PATH,
        parts: [head, model.as_bytes(), tail],
    }
}
