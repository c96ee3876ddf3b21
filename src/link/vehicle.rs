//! The vehicle's attitude, GPS and altitude: kept with their stamps, pushed at their
//! periods while fresh.

use super::*;

/// The latest attitude, GPS and altitude with their stamps and push deadlines, by
/// [`VehicleSlot`] (as in the transmit queue). Values are kept typed (18
/// bytes, not three 8-byte frames); a frame is encoded when it leaves.
#[derive(Clone, Copy, Debug)]
pub(super) struct VehicleSources {
    pub(super) attitude: Attitude,
    pub(super) gps: Gps,
    pub(super) altitude: Altitude,
    pub(super) stamp: [Instant; 3],
    pub(super) next: [Instant; 3],
    /// Bit `i`: slot `i` holds a value.
    pub(super) has: u8,
    /// Bit `i`: push slot `i` at the next poll, whatever `next` says (new data after none
    /// or stale data). Bit [`ATTITUDE_FIRST`]: the attitude frame last taken was the first
    /// since none had gone ([`ATTITUDE_SENT`] clear): if the driver refuses it, the gimbal
    /// still has none.
    pub(super) due: u8,
    /// The heading of the attitude frame last handed to the transport, 0.01°: the vehicle's
    /// heading as the gimbal knows it, which a north-referenced heading command is turned
    /// into a motor angle with.
    pub(super) attitude_sent_cdeg: i16,
    /// When that frame's attitude was measured: the gimbal's attitude is as fresh as that.
    pub(super) attitude_sent_stamp: Instant,
}

/// `VehicleSources::due`: see there.
pub(super) const ATTITUDE_FIRST: u8 = 1 << 3;
/// `VehicleSources::has`: an attitude frame was taken for the transport and not refused
/// (its heading and stamp in `attitude_sent_cdeg` and `attitude_sent_stamp`).
pub(super) const ATTITUDE_SENT: u8 = 1 << 3;

impl VehicleSources {
    pub(super) const EMPTY: Self = VehicleSources {
        attitude: Attitude::ZERO,
        gps: Gps::ZERO,
        altitude: Altitude::from_cm(0),
        stamp: [Instant::from_millis(0); 3],
        next: [Instant::from_millis(0); 3],
        has: 0,
        due: 0b111,
        attitude_sent_cdeg: 0,
        attitude_sent_stamp: Instant::from_millis(0),
    };

    pub(super) fn has(&self, slot: VehicleSlot) -> bool {
        self.has & slot.bit() != 0
    }

    pub(super) fn due(&self, slot: VehicleSlot) -> bool {
        self.due & slot.bit() != 0
    }

    pub(super) fn set_due(&mut self, slot: VehicleSlot, due: bool) {
        if due {
            self.due |= slot.bit();
        } else {
            self.due &= !slot.bit();
        }
    }

    /// When the value in `slot` was measured, if one was set.
    pub(super) fn stamp(&self, slot: VehicleSlot) -> Option<Instant> {
        if !self.has(slot) {
            return None;
        }
        self.stamp.get(slot.index()).copied()
    }

    /// Records that `slot` now holds a value measured at `stamp`.
    pub(super) fn stamped(&mut self, slot: VehicleSlot, stamp: Instant) {
        if let Some(s) = self.stamp.get_mut(slot.index()) {
            *s = stamp;
            self.has |= slot.bit();
        }
    }

    /// The value in `slot`, if one was set.
    pub(super) fn value(&self, slot: VehicleSlot) -> Option<VehicleFrame> {
        if !self.has(slot) {
            return None;
        }
        Some(match slot {
            VehicleSlot::Attitude => VehicleFrame::Attitude(self.attitude),
            VehicleSlot::Gps => VehicleFrame::Gps(self.gps),
            VehicleSlot::Altitude => VehicleFrame::Altitude(self.altitude),
        })
    }
}

impl<const Q: usize, const T: usize, M: Medium> Link<Q, T, M> {
    /// Bookkeeping before slot `slot` takes a value measured at `stamp`.
    pub(super) fn set_vehicle(&mut self, slot: VehicleSlot, stamp: Instant) {
        if !self.vehicle.has(slot) {
            self.vehicle.set_due(slot, true);
        }
        // Newer data replacing fresh data moves no deadline earlier, so the next poll need
        // only wake for a slot waiting to push at once (first value, or after going stale)
        // or for an older stamp, which brings staleness closer. (Called at every turn of a
        // main loop, this must not defeat the idle fast path.)
        let older = self
            .vehicle
            .stamp(slot)
            .is_some_and(|old| !stamp.is_at_or_after(old));
        // A serial link sends no vehicle frames: its data only waits to be used.
        if M::VEHICLE_FRAMES && (self.vehicle.due(slot) || older) {
            self.quiet = quiet::Quiet::NONE;
        }
        self.vehicle.stamped(slot, stamp);
    }

    /// Sets the latest vehicle attitude, measured at `stamp`.
    pub fn set_attitude(&mut self, attitude: Attitude, stamp: Instant) {
        self.set_vehicle(ATTITUDE, stamp);
        self.vehicle.attitude = attitude;
    }

    /// Sets the latest vehicle position, measured at `stamp`.
    pub fn set_gps(&mut self, gps: Gps, stamp: Instant) {
        self.set_vehicle(GPS, stamp);
        self.vehicle.gps = gps;
    }

    /// Sets the latest vehicle altitude, measured at `stamp`.
    pub fn set_altitude(&mut self, altitude: Altitude, stamp: Instant) {
        self.set_vehicle(ALTITUDE, stamp);
        self.vehicle.altitude = altitude;
    }

    /// Whether vehicle slot `slot` holds data that is fresh at `now`: measured at most
    /// `vehicle_stale_ms` before it, or as far after it (clock skew between producer and
    /// poller), never more than 2^31 ms before ([`Instant::is_within`]).
    pub(super) fn is_fresh(&self, slot: VehicleSlot, now: Instant) -> bool {
        self.vehicle
            .stamp(slot)
            .is_some_and(|stamp| now.is_within(stamp, u32::from(self.config.vehicle_stale_ms)))
    }

    /// Whether the gimbal references headings to north now rather than to the nose: its
    /// attitude push is on, the attitude set is fresh, and so is the attitude of the last
    /// frame that reached the transport (taken by the CAN driver and not refused,
    /// [`Link::transmit_refused`]).
    /// Attitude merely queued is not enough, nor a stream resumed after going stale until
    /// a frame of it has gone: a heading command queued
    /// beside it goes first (control frames outrank vehicle frames in the queue and on the
    /// bus), and the gimbal would take it nose-referenced. So a heading computed now is
    /// computed in the reference the gimbal will apply when it arrives. (Two frames already
    /// in the CAN controller's mailboxes go out by ID, control first: only a bus too busy
    /// to send an attitude frame before the next poll can still reorder them, and an aim's
    /// closed loop then sets the gimbal right at the next postback.)
    ///
    /// Always false on the UART, which carries no vehicle frames.
    pub fn north_referenced(&self, now: Instant) -> bool {
        let stale = u32::from(self.config.vehicle_stale_ms);
        M::VEHICLE_FRAMES
            && self.config.attitude_period_ms != 0
            && self.vehicle.has & ATTITUDE_SENT != 0
            && now.is_within(self.vehicle.attitude_sent_stamp, stale)
            && self.is_fresh(ATTITUDE, now)
    }

    /// An attitude frame, built from the value held now, is taken for the transport: the
    /// gimbal has it unless the driver refuses it (out of line, as the vehicle frames'
    /// whole path, so that a control frame's send and its report pay nothing for it).
    pub(super) fn attitude_taken(&mut self) {
        if let Some(stamp) = self.vehicle.stamp(ATTITUDE) {
            if self.vehicle.has & ATTITUDE_SENT == 0 {
                self.vehicle.due |= ATTITUDE_FIRST;
            } else {
                self.vehicle.due &= !ATTITUDE_FIRST;
            }
            self.vehicle.has |= ATTITUDE_SENT;
            self.vehicle.attitude_sent_cdeg = self.vehicle.attitude.heading_centideg();
            self.vehicle.attitude_sent_stamp = stamp;
        }
    }

    /// The driver refused an attitude frame: if it was the first, the gimbal has none yet.
    /// (A later one refused leaves the gimbal with the one before, a push period older.)
    pub(super) fn attitude_refused(&mut self) {
        if self.vehicle.due & ATTITUDE_FIRST != 0 {
            self.vehicle.has &= !ATTITUDE_SENT;
        }
    }

    /// The latest vehicle attitude set, fresh or not.
    pub fn attitude(&self) -> Option<Attitude> {
        self.vehicle.has(ATTITUDE).then_some(self.vehicle.attitude)
    }

    pub(super) fn poll_vehicle(&mut self, now: Instant, earliest: &mut Earliest) {
        if !M::VEHICLE_FRAMES {
            return;
        }
        let periods = [
            u32::from(self.config.attitude_period_ms),
            u32::from(self.config.gps_period_ms),
            u32::from(self.config.altitude_period_ms),
        ];
        let stale = u32::from(self.config.vehicle_stale_ms);
        for (slot, period) in VehicleSlot::ALL.into_iter().zip(periods) {
            let Some(stamp) = self.vehicle.stamp(slot) else {
                continue;
            };
            let Some(&next) = self.vehicle.next.get(slot.index()) else {
                continue;
            };
            if period == 0 {
                continue;
            }
            if !now.is_within(stamp, stale) {
                // Push again as soon as fresh data arrives (which marks the link dirty).
                self.vehicle.set_due(slot, true);
                continue;
            }
            let due = self.vehicle.due(slot);
            let mut next = next;
            if due || now.is_at_or_after(next) {
                next = if due {
                    now.add_millis(period)
                } else {
                    advance(next, period, now)
                };
                if let Some(n) = self.vehicle.next.get_mut(slot.index()) {
                    *n = next;
                }
                self.vehicle.set_due(slot, false);
                if self.tx.mark_vehicle(slot, &mut self.quiet) {
                    self.stats.superseded = self.stats.superseded.wrapping_add(1);
                }
            }
            earliest.offer(next);
            // Going stale changes what fresh data will do: wake up for it too.
            earliest.offer(stamp.add_millis(stale.saturating_add(1)));
        }
    }
}
