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
//! The files' parameters are [`settings::PARAMETERS`](super::settings::PARAMETERS): every
//! camera has focus (QGroundControl has no focus control but the definition's settings),
//! a camera with a thermal sensor has its palette and electronic zoom too.

use crate::ftp::File;

/// `cam_definition_version`, as in both files.
pub const VERSION: u16 = 1;
/// `cam_definition_uri`.
pub const URI: &str = "mftp://camera.xml";
/// The path the file is served at.
pub const PATH: &str = "/camera.xml";

/// The zoom camera's definition (every family but the dual light).
pub const ZOOM: &[u8] = include_bytes!("../../camera-definitions/idu-zoom.xml");
/// The dual-light camera's definition.
pub const DUAL_LIGHT: &[u8] = include_bytes!("../../camera-definitions/idu-dual-light.xml");

const ZOOM_FILES: &[File] = &[File {
    path: PATH,
    bytes: ZOOM,
}];
const DUAL_LIGHT_FILES: &[File] = &[File {
    path: PATH,
    bytes: DUAL_LIGHT,
}];

/// The files served for a camera with or without a thermal sensor.
pub(crate) fn files(thermal: bool) -> &'static [File] {
    if thermal {
        DUAL_LIGHT_FILES
    } else {
        ZOOM_FILES
    }
}
