//! The camera's video streams: every stream of the family (section 1.3), ids from 1 in the
//! family's order, the infrared one flagged thermal.
//!
//! `VIDEO_STREAM_INFORMATION` and `VIDEO_STREAM_STATUS` are answered for one stream (by id)
//! or all of them (id 0), as common.xml defines `MAV_CMD_REQUEST_MESSAGE`'s param2 for
//! them and the superseded `MAV_CMD_REQUEST_VIDEO_STREAM_*` their param1. All streams of a
//! family may not fit the outbox at once; those left are sent as it drains.
//!
//! The infrared stream is the third stream of the one camera component, not a camera of its
//! own: QGroundControl asks for every stream at once (`REQUEST_MESSAGE` 269, param2 0,
//! `VehicleCameraControl.cc`:1819-1840), keeps a `THERMAL` stream out of its stream selector
//! and plays it as its thermal view (:1640-1648, 1803-1817; HTRamsey/qgroundcontrol c15cc32),
//! where a second camera component would be listed as another camera; and its
//! `VIDEO_STREAM_STATUS` handling overwrites the stream's flags (`QGCVideoStreamInfo.cc`:28-72),
//! so the status carries `THERMAL` too. MAVSDK reports the stream as the infrared spectrum
//! (`tests/mavsdk_camera.py`).

use idu_gimbal::video::Stream;
use mavio::dialects::common::enums::{
    VideoStreamEncoding, VideoStreamStatusFlags, VideoStreamType,
};
use mavio::dialects::common::messages::{VideoStreamInformation, VideoStreamStatus};

use crate::framing::MAX_FRAME_LEN;
use crate::tx::{name, Tx};

use super::{CameraConfig, URI_CAPACITY};

/// The most streams a camera has (X3, Argus and dual light: three).
pub const MAX_STREAMS: usize = 3;

/// One video stream: what it is and its RTSP address.
#[derive(Clone, PartialEq, Eq, Debug)]
pub struct VideoStream {
    /// Which stream of the family.
    pub kind: Stream,
    pub(crate) uri: heapless::String<URI_CAPACITY>,
}

impl VideoStream {
    /// The stream's URI.
    pub fn uri(&self) -> &str {
        &self.uri
    }

    /// Whether the stream is thermal imaging (the dual light's infrared stream).
    pub fn is_thermal(&self) -> bool {
        self.kind == Stream::Infrared
    }

    fn flags(&self) -> VideoStreamStatusFlags {
        if self.is_thermal() {
            VideoStreamStatusFlags::RUNNING | VideoStreamStatusFlags::THERMAL
        } else {
            VideoStreamStatusFlags::RUNNING
        }
    }
}

/// Which of the streams still wait for their message, one bit per stream (bit 0: id 1).
#[derive(Clone, Copy, PartialEq, Eq, Debug, Default)]
pub(crate) struct Pending {
    information: u8,
    status: u8,
}

/// What a request's stream id names: one stream, all (0), or none of ours.
pub(crate) fn selection(config: &CameraConfig, id: f32) -> Option<u8> {
    let count = config.streams().len();
    let all = super::low_bits(count);
    if id == 0.0 {
        return Some(all);
    }
    // Ids are 1..=count: whole and small, so the cast is exact.
    (id >= 1.0 && id <= count as f32 && id == libm::truncf(id))
        .then(|| 1u8 << (id as u8).saturating_sub(1))
}

impl Pending {
    /// Streams (a [`selection`]) to describe.
    pub(crate) fn information(&mut self, streams: u8) {
        self.information |= streams;
    }

    /// Streams (a [`selection`]) whose status to send.
    pub(crate) fn status(&mut self, streams: u8) {
        self.status |= streams;
    }

    pub(crate) fn any(&self) -> bool {
        self.information | self.status != 0
    }

    /// Sends what waits, as far as the outbox has room; `zoom` the ratio now.
    pub(crate) fn send(&mut self, config: &CameraConfig, zoom: f32, tx: &mut Tx<'_>) {
        let count = config.streams().len() as u8;
        // The main camera's horizontal angle at the zoom now, whole degrees; the infrared
        // stream's lens is not configured: 0, unknown ([`super::fov`]).
        let visible_hfov = super::fov::stream_hfov(config, zoom);
        for (i, stream) in config.streams().iter().enumerate() {
            let hfov = if stream.is_thermal() { 0 } else { visible_hfov };
            let bit = 1u8 << i;
            // The index is below MAX_STREAMS: the id fits.
            let id = (i as u8).saturating_add(1);
            if self.information & bit != 0 {
                if tx.out.room() < MAX_FRAME_LEN {
                    return;
                }
                send_information(config, stream, id, count, hfov, tx);
                self.information &= !bit;
            }
            if self.status & bit != 0 {
                if tx.out.room() < MAX_FRAME_LEN {
                    return;
                }
                send_status(config, stream, id, hfov, tx);
                self.status &= !bit;
            }
        }
    }
}

fn send_information(
    config: &CameraConfig,
    stream: &VideoStream,
    id: u8,
    count: u8,
    hfov: u16,
    tx: &mut Tx<'_>,
) {
    let (resolution_h, resolution_v) = config.resolution.unwrap_or((0, 0));
    let s = VideoStreamInformation {
        stream_id: id,
        count,
        type_: VideoStreamType::Rtsp,
        flags: stream.flags(),
        framerate: 0.0,
        resolution_h,
        resolution_v,
        bitrate: 0,
        rotation: 0,
        hfov,
        name: name(stream.kind.name()),
        uri: name::<URI_CAPACITY>(stream.uri()),
        encoding: VideoStreamEncoding::Unknown,
        camera_device_id: 0,
    };
    tx.out.send(config.component, &s);
}

/// A stream's status (MAVSDK's camera plugin asks for it before it reports the stream):
/// running; what the gimbal does not report is 0 (unknown).
fn send_status(config: &CameraConfig, stream: &VideoStream, id: u8, hfov: u16, tx: &mut Tx<'_>) {
    let (resolution_h, resolution_v) = config.resolution.unwrap_or((0, 0));
    let s = VideoStreamStatus {
        stream_id: id,
        flags: stream.flags(),
        framerate: 0.0,
        resolution_h,
        resolution_v,
        bitrate: 0,
        rotation: 0,
        hfov,
        camera_device_id: 0,
    };
    tx.out.send(config.component, &s);
}
