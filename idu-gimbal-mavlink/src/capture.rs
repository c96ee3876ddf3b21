//! Image capture as `MAV_CMD_IMAGE_START_CAPTURE` defines it, run by the bridge: one
//! image now, or images at an interval (a count of them, or until stopped), each reported
//! when it is taken with consecutive indexes, and the latest ones kept for re-requests.
//!
//! common.xml, `MAV_CMD_IMAGE_START_CAPTURE`: param2 is "the desired elapsed time between
//! two consecutive pictures (in seconds)", param3 "the total number of images to capture.
//! 0 to capture forever/until MAV_CMD_IMAGE_STOP_CAPTURE", param4 "capture sequence number
//! starting from 1. This is only valid for single-capture (param3 == 1), otherwise set to
//! 0. Increment the capture ID for each capture command to prevent double captures when a
//! command is re-transmitted". So:
//!
//! - the gimbal's own burst and time-lapse modes are not used: they take images at times
//!   the gimbal does not report, so their images could not be reported when taken. Each
//!   image is the gimbal's single shot, commanded on the bridge's schedule (the first at
//!   once), and reported with `CAMERA_IMAGE_CAPTURED` when that command is queued;
//! - a single capture from the client whose last single capture had the same sequence
//!   number, within [`REPEAT_WINDOW_MS`] of it, is a re-transmission: it is acknowledged
//!   again and takes no picture (another client's, or one that starts numbering again
//!   later, is a new picture);
//! - the last [`HISTORY`] images are kept, so `MAV_CMD_REQUEST_MESSAGE` for
//!   `CAMERA_IMAGE_CAPTURED` (param2 the first index or −1 for all, param3 0, −1 or the
//!   last index) is answered for them (MAVSDK asks again for indexes it missed).

use idu_gimbal::Instant;

use crate::attitude::YawPitch;

/// Images kept for re-requests.
pub const HISTORY: usize = 16;
/// The shortest interval between scheduled images, ms. The document gives no rate for the
/// gimbal's single shot; 100 ms keeps a schedule within the CAN queue's pace (a command
/// every tick would starve the attitude setpoints).
pub const MIN_INTERVAL_MS: u32 = 100;
/// The longest interval, ms (an hour): longer is taken as a mistake.
pub const MAX_INTERVAL_MS: u32 = 3_600_000;
/// How long after a single capture the same client's same sequence number is taken for
/// its re-transmission, ms: the command protocol re-sends within its timeouts, seconds
/// (a client that restarts and numbers from 1 again takes longer than that to come back).
pub const REPEAT_WINDOW_MS: u32 = 10_000;
/// The largest sequence number, 2^24: every whole number up to it is exact in param4's
/// `f32`.
pub const MAX_SEQUENCE: u32 = 1 << 24;

/// Why a capture command was refused.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum CaptureError {
    /// param3 (count) is not a whole number in [0, 65535].
    Count,
    /// param2 (interval) is not finite or, for more than one image, outside
    /// [[`MIN_INTERVAL_MS`], [`MAX_INTERVAL_MS`]].
    Interval,
    /// param4 (sequence number) of a single capture is not a whole number in
    /// [0, [`MAX_SEQUENCE`]] (0: none given).
    Sequence,
}

/// Where an image is taken from: the vehicle's position and the camera's attitude.
#[derive(Clone, Copy, PartialEq, Eq, Debug, Default)]
pub struct Vantage {
    /// The vehicle's position: lat, lon (1e-7°), alt and relative alt (mm); `None` without
    /// one.
    pub position: Option<[i32; 4]>,
    /// The camera's yaw from north and pitch from the horizon, 0.01° (the latest postback's
    /// motor angle and pitch, with the vehicle's heading); `None` without a postback or a
    /// fresh vehicle heading.
    pub attitude: Option<(i16, i16)>,
}

impl Vantage {
    /// The camera's attitude as an earth-frame (NED) quaternion, NaN when unknown.
    /// common.xml names no frame for `CAMERA_IMAGE_CAPTURED.q` or `CAMERA_FOV_STATUS.q`;
    /// the messages' producers give it so (PX4's camera_feedback rotates a vehicle-frame
    /// gimbal attitude by the vehicle's yaw).
    pub fn quaternion(&self) -> [f32; 4] {
        self.attitude.map_or([f32::NAN; 4], |(yaw, pitch)| {
            YawPitch {
                yaw_rad: (f32::from(yaw) / 100.0).to_radians(),
                pitch_rad: (f32::from(pitch) / 100.0).to_radians(),
            }
            .to_quaternion()
        })
    }
}

/// One image taken: what `CAMERA_IMAGE_CAPTURED` reports of it.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub struct Image {
    /// Its index, from 0, consecutive.
    pub index: i32,
    /// When it was commanded.
    pub at: Instant,
    /// Where it was taken from.
    pub vantage: Vantage,
}

/// What a start command asks for, validated.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub struct Request {
    /// ms between images (0 for a single image).
    pub interval_ms: u32,
    /// Images to take; 0 until stopped.
    pub count: u16,
    /// The single capture's sequence number (0: none given; always 0 for more than one
    /// image, whose param4 common.xml leaves unused).
    pub sequence: u32,
}

impl Request {
    /// Reads `MAV_CMD_IMAGE_START_CAPTURE`'s param2 (interval, s), param3 (count) and
    /// param4 (sequence number).
    pub fn from_params(interval_s: f32, count: f32, sequence: f32) -> Result<Self, CaptureError> {
        let whole =
            |v: f32, max: f32| v.is_finite() && (0.0..=max).contains(&v) && v == libm::truncf(v);
        if !whole(count, 65_535.0) {
            return Err(CaptureError::Count);
        }
        // In range and whole: exact.
        let count = count as u16;
        let sequence = match count {
            // In range and whole: exact.
            1 if whole(sequence, MAX_SEQUENCE as f32) => sequence as u32,
            1 => return Err(CaptureError::Sequence),
            _ => 0,
        };
        if count == 1 {
            // One image: the interval does not matter (common.xml), but must be a number.
            if !interval_s.is_finite() {
                return Err(CaptureError::Interval);
            }
            return Ok(Request {
                interval_ms: 0,
                count,
                sequence,
            });
        }
        let ms = interval_s * 1000.0;
        if !(ms.is_finite() && (MIN_INTERVAL_MS as f32..=MAX_INTERVAL_MS as f32).contains(&ms)) {
            return Err(CaptureError::Interval);
        }
        Ok(Request {
            // In range: exact to the millisecond after rounding.
            interval_ms: libm::roundf(ms) as u32,
            count,
            sequence: 0,
        })
    }
}

/// A schedule in progress.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
struct Schedule {
    interval_ms: u32,
    /// Images still to take; `None` until stopped.
    left: Option<u16>,
    /// When the next is due.
    next: Instant,
}

/// The last single capture with a sequence number: who asked, the number, when.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
struct Single {
    client: (u8, u8),
    sequence: u32,
    at: Instant,
}

/// The capture state: schedule, sequence, history.
#[derive(Clone, Debug)]
pub struct Capture {
    schedule: Option<Schedule>,
    last_single: Option<Single>,
    next_index: i32,
    history: heapless::Deque<Image, HISTORY>,
}

impl Default for Capture {
    fn default() -> Self {
        Self::new()
    }
}

/// What a start command leads to.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Start {
    /// The first image is due now ([`Capture::due`] says so).
    Started,
    /// A re-transmitted single capture: acknowledge, take nothing.
    Repeated,
}

impl Capture {
    /// No capture yet.
    pub const fn new() -> Self {
        Capture {
            schedule: None,
            last_single: None,
            next_index: 0,
            history: heapless::Deque::new(),
        }
    }

    /// Whether `request` from `client` at `now` repeats the last single capture: the same
    /// client's same sequence number (not 0), within [`REPEAT_WINDOW_MS`]. A
    /// re-transmission, to acknowledge without taking a picture.
    pub fn is_repeat(&self, request: &Request, client: (u8, u8), now: Instant) -> bool {
        request.sequence != 0
            && self.last_single.is_some_and(|last| {
                last.client == client
                    && last.sequence == request.sequence
                    && now.is_within(last.at, REPEAT_WINDOW_MS)
            })
    }

    /// Starts a capture from `client` (replacing one in progress); the first image is due
    /// at once. A repeat ([`Capture::is_repeat`]) starts nothing.
    pub fn start(&mut self, request: Request, client: (u8, u8), now: Instant) -> Start {
        if self.is_repeat(&request, client, now) {
            return Start::Repeated;
        }
        if request.sequence != 0 {
            self.last_single = Some(Single {
                client,
                sequence: request.sequence,
                at: now,
            });
        }
        self.schedule = Some(Schedule {
            interval_ms: request.interval_ms,
            left: (request.count != 0).then_some(request.count),
            next: now,
        });
        Start::Started
    }

    /// Stops the capture in progress.
    pub fn stop(&mut self) {
        self.schedule = None;
    }

    /// Whether images are being taken at an interval (for `CAMERA_CAPTURE_STATUS`), and
    /// the interval in ms.
    pub fn interval(&self) -> Option<u32> {
        self.schedule
            .filter(|s| s.interval_ms > 0)
            .map(|s| s.interval_ms)
    }

    /// Whether an image is due at `now`.
    pub fn due(&self, now: Instant) -> bool {
        self.schedule.is_some_and(|s| now.is_at_or_after(s.next))
    }

    /// The image due was commanded at `now`: records it and schedules the next. The next
    /// is due one interval after this one was due, so a late poll does not shift the
    /// schedule (unless it is more than an interval late: then one interval from now).
    pub fn taken(&mut self, now: Instant, vantage: Vantage) -> Image {
        let image = Image {
            index: self.next_index,
            at: now,
            vantage,
        };
        self.next_index = self.next_index.wrapping_add(1);
        if self.history.is_full() {
            let _ = self.history.pop_front();
        }
        // Room was made above.
        let _ = self.history.push_back(image);
        if let Some(s) = self.schedule.as_mut() {
            let left = s.left.map(|n| n.saturating_sub(1));
            if left == Some(0) {
                self.schedule = None;
            } else {
                s.left = left;
                let next = s.next.add_millis(s.interval_ms);
                s.next = if now.is_at_or_after(next) && now.millis_since(next) >= s.interval_ms {
                    now.add_millis(s.interval_ms)
                } else {
                    next
                };
            }
        }
        image
    }

    /// Images taken so far (wrapping as the index does).
    pub fn count(&self) -> i32 {
        self.next_index
    }

    /// The kept images with indexes in `first..=last`, oldest first.
    pub fn history(&self, first: i32, last: i32) -> impl Iterator<Item = &Image> {
        self.history
            .iter()
            .filter(move |i| i.index >= first && i.index <= last)
    }

    /// The oldest index kept (the next to be taken when none is).
    pub fn oldest_kept(&self) -> i32 {
        self.history.front().map_or(self.next_index, |i| i.index)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A ground station's (system, component).
    const GCS: (u8, u8) = (255, 190);

    fn t(ms: u32) -> Instant {
        Instant::from_millis(ms)
    }

    #[test]
    fn params_read_as_common_xml_defines_them() {
        // One image: sequence kept, interval ignored.
        assert_eq!(
            Request::from_params(0.0, 1.0, 7.0),
            Ok(Request {
                interval_ms: 0,
                count: 1,
                sequence: 7
            })
        );
        // Five images 0.5 s apart: the sequence is only for single captures.
        assert_eq!(
            Request::from_params(0.5, 5.0, 3.0),
            Ok(Request {
                interval_ms: 500,
                count: 5,
                sequence: 0
            })
        );
        // Until stopped, every 2 s.
        assert_eq!(
            Request::from_params(2.0, 0.0, 0.0).map(|r| (r.interval_ms, r.count)),
            Ok((2_000, 0))
        );
        assert_eq!(
            Request::from_params(0.05, 0.0, 0.0),
            Err(CaptureError::Interval)
        );
        assert_eq!(
            Request::from_params(0.0, 3.0, 0.0),
            Err(CaptureError::Interval)
        );
        assert_eq!(
            Request::from_params(f32::NAN, 1.0, 0.0),
            Err(CaptureError::Interval)
        );
        assert_eq!(
            Request::from_params(3_601.0, 2.0, 0.0),
            Err(CaptureError::Interval)
        );
        assert_eq!(
            Request::from_params(1.0, 2.5, 0.0),
            Err(CaptureError::Count)
        );
        assert_eq!(
            Request::from_params(1.0, -1.0, 0.0),
            Err(CaptureError::Count)
        );
        assert_eq!(
            Request::from_params(1.0, 70_000.0, 0.0),
            Err(CaptureError::Count)
        );
    }

    #[test]
    fn a_count_at_an_interval_takes_each_image_on_time_with_consecutive_indexes() {
        let mut c = Capture::new();
        let r = Request::from_params(0.5, 3.0, 0.0).unwrap();
        assert_eq!(c.start(r, GCS, t(1_000)), Start::Started);
        let mut taken = Vec::new();
        for ms in 1_000..5_000 {
            if c.due(t(ms)) {
                taken.push((c.taken(t(ms), Vantage::default()).index, ms));
            }
        }
        assert_eq!(taken, [(0, 1_000), (1, 1_500), (2, 2_000)]);
        assert_eq!(c.interval(), None, "done after three");
        assert_eq!(c.count(), 3);
    }

    #[test]
    fn a_late_poll_does_not_shift_the_schedule_and_it_runs_across_the_tick_wrap() {
        let mut c = Capture::new();
        let start = u32::MAX - 700;
        c.start(Request::from_params(1.0, 0.0, 0.0).unwrap(), GCS, t(start));
        let mut times = Vec::new();
        // Polled every 7 ms: each image within 7 ms of its slot, slots 1 s apart.
        let mut ms = start;
        for _ in 0..600 {
            if c.due(t(ms)) {
                c.taken(t(ms), Vantage::default());
                times.push(ms.wrapping_sub(start));
            }
            ms = ms.wrapping_add(7);
        }
        assert_eq!(times.len(), 5, "{times:?}");
        for (k, dt) in times.iter().enumerate() {
            let slot = k as u32 * 1_000;
            assert!(*dt >= slot && *dt < slot + 7, "{times:?}");
        }
        c.stop();
        assert!(!c.due(t(ms.wrapping_add(10_000))));
    }

    #[test]
    fn a_late_image_keeps_its_slots_until_it_is_an_interval_behind() {
        let mut c = Capture::new();
        c.start(Request::from_params(1.0, 0.0, 0.0).unwrap(), GCS, t(0));
        let v = Vantage::default();
        c.taken(t(0), v);
        assert!(!c.due(t(999)) && c.due(t(1_000)));
        // Half an interval late: the next slot is still 2,000.
        c.taken(t(1_500), v);
        assert!(!c.due(t(1_999)) && c.due(t(2_000)));
        // 1,500 late, less than an interval past the next slot (3,000): that one at once.
        c.taken(t(3_500), v);
        assert!(c.due(t(3_500)));
        // An interval and more past the next slot (4,000): from now on, 6,100.
        c.taken(t(5_100), v);
        assert!(!c.due(t(6_099)) && c.due(t(6_100)));
    }

    #[test]
    fn a_single_capture_has_no_interval_nor_a_sequence_that_is_not_whole() {
        let mut c = Capture::new();
        c.start(Request::from_params(0.0, 1.0, 0.0).unwrap(), GCS, t(0));
        assert!(c.due(t(0)));
        assert_eq!(c.interval(), None);
        // A sequence number that is no whole number in [0, 2^24] is refused, not read
        // as "none".
        for sequence in [2.5, f32::NAN, f32::INFINITY, -1.0, 16_777_218.0] {
            assert_eq!(
                Request::from_params(0.0, 1.0, sequence),
                Err(CaptureError::Sequence),
                "{sequence}"
            );
        }
        assert_eq!(
            Request::from_params(0.0, 1.0, 16_777_216.0).map(|r| r.sequence),
            Ok(16_777_216)
        );
    }

    #[test]
    fn a_retransmitted_single_capture_takes_no_second_picture() {
        let mut c = Capture::new();
        let once = Request::from_params(0.0, 1.0, 1.0).unwrap();
        assert_eq!(c.start(once, GCS, t(0)), Start::Started);
        c.taken(t(0), Vantage::default());
        assert!(!c.due(t(1)));
        assert_eq!(c.start(once, GCS, t(5)), Start::Repeated);
        assert!(!c.due(t(6)));
        let next = Request::from_params(0.0, 1.0, 2.0).unwrap();
        assert_eq!(c.start(next, GCS, t(10)), Start::Started);
        // Sequence 0 means "none given": never taken for a repeat.
        let plain = Request::from_params(0.0, 1.0, 0.0).unwrap();
        c.taken(t(10), Vantage::default());
        assert_eq!(c.start(plain, GCS, t(20)), Start::Started);
        c.taken(t(20), Vantage::default());
        assert_eq!(c.start(plain, GCS, t(30)), Start::Started);
    }

    #[test]
    fn only_the_same_clients_number_soon_after_is_a_repeat() {
        let mut c = Capture::new();
        let one = Request::from_params(0.0, 1.0, 1.0).unwrap();
        assert_eq!(c.start(one, GCS, t(0)), Start::Started);
        // Another client's 1 is its own first picture.
        assert_eq!(c.start(one, (1, 1), t(100)), Start::Started);
        // The first client's 1 again: a repeat within the window, a new picture after it
        // (a client that restarted and numbers from 1 again).
        assert_eq!(c.start(one, GCS, t(200)), Start::Started);
        assert_eq!(
            c.start(one, GCS, t(200 + REPEAT_WINDOW_MS)),
            Start::Repeated
        );
        assert_eq!(
            c.start(one, GCS, t(200 + 2 * REPEAT_WINDOW_MS + 1)),
            Start::Started
        );
    }

    #[test]
    fn the_history_keeps_the_latest_images() {
        let mut c = Capture::new();
        for k in 0..20u32 {
            c.start(Request::from_params(0.0, 1.0, 0.0).unwrap(), GCS, t(k));
            c.taken(
                t(k),
                Vantage {
                    position: Some([k as i32, 0, 0, 0]),
                    attitude: None,
                },
            );
        }
        assert_eq!(c.oldest_kept(), 4);
        let kept: Vec<i32> = c.history(0, i32::MAX).map(|i| i.index).collect();
        assert_eq!(kept, (4..20).collect::<Vec<_>>());
        let one: Vec<_> = c.history(7, 7).collect();
        assert_eq!(one.len(), 1);
        assert_eq!(one[0].vantage.position, Some([7, 0, 0, 0]));
    }
}
