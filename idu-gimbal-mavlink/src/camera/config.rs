//! What a camera is configured with (its component id, video streams, zoom range,
//! resolution, field of view), and what a gimbal type implies: its zoom range and the
//! model name `CAMERA_INFORMATION` gives.

use core::fmt;

use idu_gimbal::video::{self, Family, Stream, VideoError};
use idu_gimbal::wire::postback::GimbalType;

use super::fov::FieldOfView;
use super::stream::{VideoStream, MAX_STREAMS};

/// `MAV_COMP_ID_CAMERA`.
pub const CAMERA_COMPONENT: u8 = 100;
/// The longest stream URI `VIDEO_STREAM_INFORMATION` holds.
pub const URI_CAPACITY: usize = 160;
/// MAVLink FTP sessions open at once (a ground station and a second client).
pub const FTP_SESSIONS: usize = 2;

/// A stream URI longer than `VIDEO_STREAM_INFORMATION`'s field: a configuration error,
/// never a truncation.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct UriTooLong {
    /// The URI's length, bytes.
    pub len: usize,
    /// The most the field holds.
    pub max: usize,
}

impl fmt::Display for UriTooLong {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "stream URI is {} bytes; VIDEO_STREAM_INFORMATION holds at most {}",
            self.len, self.max
        )
    }
}

/// Why a camera's streams could not be configured.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum StreamError {
    /// A stream's address could not be built (see [`VideoError`]).
    Video(VideoError),
    /// A stream's address is longer than the message holds.
    UriTooLong(UriTooLong),
}

impl fmt::Display for StreamError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            StreamError::Video(e) => write!(f, "{e}"),
            StreamError::UriTooLong(e) => write!(f, "{e}"),
        }
    }
}

/// The camera component's configuration.
#[derive(Clone, PartialEq, Debug)]
pub struct CameraConfig {
    /// Component id (default [`CAMERA_COMPONENT`], 100).
    pub component: u8,
    /// The largest optical zoom ratio; `None` (the default): from the postback's gimbal
    /// type (see [`zoom_max_of`]).
    pub zoom_max: Option<f32>,
    /// The streams' resolution (horizontal, vertical), when known: the vendor document
    /// gives none, so `None` by default (reported as 0, "unknown").
    pub resolution: Option<(u16, u16)>,
    /// The main camera's field of view at 1×, when known: no source gives it for any
    /// family, so `None` by default (see [`fov`](super::fov)).
    pub fov: Option<FieldOfView>,
    streams: heapless::Vec<VideoStream, MAX_STREAMS>,
}

// Every family's streams fit in a configuration, checked at compile time: the constructors
// push them without a case for a full vector.
const _: () = {
    let mut families: &[Family] = &Family::ALL;
    while let [family, rest @ ..] = families {
        assert!(family.streams().len() <= MAX_STREAMS);
        families = rest;
    }
};

/// `uri` in a URI field, or how long it is.
fn uri_field(uri: &str) -> Result<heapless::String<URI_CAPACITY>, UriTooLong> {
    heapless::String::try_from(uri).map_err(|_| UriTooLong {
        len: uri.len(),
        max: URI_CAPACITY,
    })
}

impl CameraConfig {
    /// A camera with one video stream, the main one, at `uri` (e.g. from
    /// `idu_gimbal::video::Camera::url`).
    pub fn new(uri: &str) -> Result<Self, UriTooLong> {
        let mut streams = heapless::Vec::new();
        // Never refused: every family's streams fit (checked at compile time), one does.
        let _ = streams.push(VideoStream {
            kind: Stream::Main,
            uri: uri_field(uri)?,
        });
        Ok(CameraConfig {
            component: CAMERA_COMPONENT,
            zoom_max: None,
            resolution: None,
            fov: None,
            streams,
        })
    }

    /// A camera with every stream of its family (section 1.3), in the family's order: the
    /// dual light's infrared stream makes it a camera with a thermal sensor (its settings
    /// and definition file, the infrared image as a tracking source).
    pub fn with_streams_of(camera: &video::Camera<'_>) -> Result<Self, StreamError> {
        let mut streams = heapless::Vec::new();
        for &kind in camera.family.streams() {
            let mut uri = heapless::String::<URI_CAPACITY>::new();
            camera.write_url(kind, &mut uri).map_err(|e| match e {
                VideoError::DoesNotFit { len } => StreamError::UriTooLong(UriTooLong {
                    len,
                    max: URI_CAPACITY,
                }),
                e => StreamError::Video(e),
            })?;
            // Never refused: every family's streams fit (checked at compile time).
            let _ = streams.push(VideoStream { kind, uri });
        }
        Ok(CameraConfig {
            component: CAMERA_COMPONENT,
            zoom_max: None,
            resolution: None,
            fov: None,
            streams,
        })
    }

    /// The main stream's URI.
    pub fn uri(&self) -> &str {
        self.streams.first().map_or("", VideoStream::uri)
    }

    /// The video streams, ids 1, 2, ... in this order.
    pub fn streams(&self) -> &[VideoStream] {
        &self.streams
    }

    /// Whether the camera has a thermal sensor (an infrared stream).
    pub fn has_thermal(&self) -> bool {
        self.streams.iter().any(VideoStream::is_thermal)
    }
}

/// The optical zoom range of a gimbal type, as its name in the vendor document gives it:
/// 30× for the X30, X30T and 30× dual light, 3.5× for the 3.5× and 3.5× dual light;
/// `None` where the document does not say (laser ranging, A2000, unknown codes).
pub fn zoom_max_of(t: GimbalType) -> Option<f32> {
    match t {
        GimbalType::X30 | GimbalType::X30T | GimbalType::DualLight30x => Some(30.0),
        GimbalType::Zoom3_5x | GimbalType::DualLight3_5x => Some(3.5),
        GimbalType::LaserRanging | GimbalType::A2000 | GimbalType::Unknown(_) => None,
    }
}

/// The model name of a gimbal type the document does not list, or not known yet.
pub(super) const UNKNOWN_MODEL: &str = "IDU camera";

/// The camera's model name for a gimbal type (`CAMERA_INFORMATION.model_name`): the
/// document's name, with characters a file name cannot hold replaced by `-`, because
/// QGroundControl names its cached definition `<vendor>_<model>_<version>.xml`
/// (`VehicleCameraControl.cc` `_cacheFile`) and a `/` made the download fail ("X30/X30GT").
/// A type the document does not list is `IDU camera`.
pub fn camera_model(t: GimbalType) -> &'static str {
    match t {
        GimbalType::X30 => "X30-X30GT",
        t => t.model_name().unwrap_or(UNKNOWN_MODEL),
    }
}
