//! Footprint of the serial driver: `footprint_base` plus a `SerialGimbal` (default queue, in
//! a static) that a firmware drives with every kind of call the serial path offers:
//! commands, a rate hold, vehicle data observed for point-at, polling, events and counters.
//! See `examples/common/footprint.rs` and `scripts/size-report.sh`.
#![cfg_attr(target_os = "none", no_std, no_main)]

#[cfg(target_os = "none")]
#[path = "common/footprint.rs"]
mod footprint;

#[cfg(target_os = "none")]
#[cortex_m_rt::entry]
fn main() -> ! {
    use footprint::{input, output, RegPort};
    use idu_gimbal::wire::control::{GimbalCommand, Heading, Photo, Pitch, Rate, Video, ZoomRatio};
    use idu_gimbal::wire::vehicle::{Altitude, Attitude, Gps};
    use idu_gimbal::{Config, Event, Instant, SerialGimbal};

    let Some(gimbal) = cortex_m::singleton!(
        : SerialGimbal<RegPort> = SerialGimbal::new(RegPort, Config::default())
    ) else {
        cortex_m::asm::udf()
    };
    footprint::use_mem_builtins();
    loop {
        footprint::can_skeleton();
        let now = Instant::from_millis(input(4));
        let arg = input(6);
        let a = arg as i16;
        let b = (arg >> 16) as i16;
        let sent = match input(5) & 15 {
            0 => Pitch::from_deci(a).map(|p| gimbal.send(GimbalCommand::Pitch(p)).is_ok()),
            1 => {
                Heading::from_deci(a as u16).map(|h| gimbal.send(GimbalCommand::Heading(h)).is_ok())
            }
            2 => Ok(gimbal.send(GimbalCommand::Recenter).is_ok()),
            3 => ZoomRatio::from_centi(a as u16)
                .map(|z| gimbal.send(GimbalCommand::ZoomRatio(z)).is_ok()),
            4 => Ok(gimbal.send(GimbalCommand::Photo(Photo::Single)).is_ok()),
            5 => Ok(gimbal.send(GimbalCommand::Video(Video::Start)).is_ok()),
            6 => Ok(gimbal.send(GimbalCommand::Video(Video::Stop)).is_ok()),
            7 => Rate::from_centi(a, b).map(|r| gimbal.set_rate(r, now).is_ok()),
            8 => {
                gimbal.stop_rate();
                Ok(true)
            }
            10 => Attitude::from_centideg(a, b, 0).map(|att| {
                gimbal.observe_attitude(att, now);
                true
            }),
            11 => Gps::from_e7(input(7) as i32, input(8) as i32).map(|g| {
                gimbal.observe_gps(g, now);
                true
            }),
            12 => {
                gimbal.observe_altitude(Altitude::from_cm(input(7) as i32), now);
                Ok(true)
            }
            _ => Ok(false),
        };
        output(u32::from(sent == Ok(true)));

        output(u32::from(gimbal.poll(now).is_ok()));
        while let Some(event) = gimbal.next_event() {
            output(match event {
                Event::Postback => gimbal
                    .latest_postback(now)
                    .map_or(0, |(p, _)| p.pitch as u32 ^ u32::from(p.heading)),
                Event::LinkUp => 1,
                Event::LinkDown => 2,
                Event::RateHoldExpired => 3,
                Event::TargetUnreachable { elevation_cdeg } => elevation_cdeg as u32,
            });
        }
        output(gimbal.stats().link.postbacks);
        output(u32::from(gimbal.is_link_up()));
    }
}

#[cfg(not(target_os = "none"))]
fn main() {}
