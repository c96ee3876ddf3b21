//! Footprint of the MAVLink bridge: `footprint_driver` (the core's CAN driver, driven with
//! every kind of call) plus a `Bridge` with a camera in front of it, fed MAVLink bytes from
//! an opaque serial port and writing back to it. `scripts/size-report.sh` subtracts
//! `footprint_driver`: what remains is everything the bridge adds beyond the plain CAN
//! driver. Never run (the runner refuses it); only its size matters.
#![no_std]
#![no_main]

// A module of each program, not a library: see its header.
#[path = "../footprint.rs"]
mod footprint;

#[cortex_m_rt::entry]
fn main() -> ! {
    use footprint::{input, output, RegCan, RegPort};
    use idu_gimbal::port::Uart;
    use idu_gimbal::video::{Camera, Family};
    use idu_gimbal::{CanPort, Config, Instant, Link};
    use idu_gimbal_mavlink::camera::fov::FieldOfView;
    use idu_gimbal_mavlink::camera::CameraConfig;
    use idu_gimbal_mavlink::{Bridge, BridgeConfig, SerialInput};

    // Either family, chosen at run time, so that everything the camera can be is linked:
    // both definition files, the thermal settings.
    let family = if input(5) == 0 {
        Family::X3
    } else {
        Family::DualLight
    };
    let mut camera = CameraConfig::with_streams_of(&Camera::new(family)).ok();
    // A lens, as a firmware that knows its camera's sets it: the field of view's code linked.
    if let Some(c) = camera.as_mut() {
        c.fov = FieldOfView::from_degrees(input(6) as f32, input(7) as f32).ok();
    }
    // With the `signing` feature, a key as a firmware reads it from its storage.
    #[cfg(feature = "signing")]
    let signing = Some(idu_gimbal_mavlink::signing::SigningConfig {
        key: [input(8) as u8; 32],
        link_id: input(9) as u8,
    });
    // As a firmware does with a configuration it got wrong: it cannot go on.
    let Ok(config) = BridgeConfig {
        camera,
        #[cfg(feature = "signing")]
        signing,
        ..BridgeConfig::default()
    }
    .check() else {
        cortex_m::asm::udf()
    };
    let Some(bridge) = cortex_m::singleton!(: Bridge = Bridge::new(config)) else {
        cortex_m::asm::udf()
    };
    // As `footprint_driver` holds them.
    let Some((link, can)) = cortex_m::singleton!(
        : (Link, CanPort<RegCan>) = (Link::new(Config::default()), CanPort::new(RegCan))
    ) else {
        cortex_m::asm::udf()
    };
    footprint::use_mem_builtins();
    let mut port = RegPort;
    // What the bridge has not taken of the line's bytes (a frame waits for room in its outbox).
    let mut from_line: SerialInput<64> = SerialInput::new();
    loop {
        // The same as `footprint_driver`: the UART used directly, the link and port driven.
        footprint::port_skeleton();
        footprint::drive(link, can);
        let now = Instant::from_millis(input(4));
        let _ = from_line.receive(bridge, link, now, |buf| port.read(buf));
        bridge.poll(link, now);
        let bytes = bridge.transmit_bytes();
        if let Ok(n) = port.write(bytes) {
            bridge.transmit_written(n);
        }
        output(bridge.stats().acks);
    }
}
