use super::*;
use core::num::NonZeroU8;
use proptest::prelude::*;

fn g(c: GimbalCommand) -> Command {
    Command::Gimbal(c)
}

fn d(c: DualLightCommand) -> Command {
    Command::DualLight(c)
}

fn nz(n: u8) -> NonZeroU8 {
    NonZeroU8::new(n).unwrap()
}

/// Encodes to exactly `bytes`, and `bytes` decodes to exactly the command.
#[track_caller]
fn assert_vector(cmd: Command, bytes: [u8; 8]) {
    assert_eq!(cmd.encode(), bytes, "encode {cmd:?}");
    assert_eq!(Command::decode(&bytes), Ok(cmd), "decode {bytes:02X?}");
    let frame = cmd.to_frame();
    assert_eq!((frame.id, frame.data), (0x0000_0F01, bytes));
}

#[test]
fn command_keeps_no_tag_of_its_own() {
    // `GimbalCommand`'s word-sized tag leaves room for the dual-light commands beside
    // it; if `Command` grew a tag again, `encode`'s angle path would load it too.
    assert_eq!(
        core::mem::size_of::<Command>(),
        core::mem::size_of::<GimbalCommand>()
    );
}

#[test]
fn notes_vectors() {
    // the protocol notes / section 2.2.1 of the document, byte for byte.
    assert_vector(
        g(GimbalCommand::Rate(Rate::new(-5.0, 0.0).unwrap())),
        [0x0F, 0x04, 0x0C, 0xFE, 0x00, 0x00, 0x00, 0x00],
    );
    assert_vector(
        g(GimbalCommand::Rate(Rate::new(0.0, 5.0).unwrap())),
        [0x0F, 0x04, 0x00, 0x00, 0xF4, 0x01, 0x00, 0x00],
    );
    assert_vector(
        g(GimbalCommand::Heading(Heading::new(45.0).unwrap())),
        [0x0F, 0x08, 0x01, 0xC2, 0x01, 0x00, 0x00, 0x00],
    );
    assert_vector(
        g(GimbalCommand::Pitch(Pitch::new(-45.0).unwrap())),
        [0x0F, 0x08, 0x02, 0x3E, 0xFE, 0x00, 0x00, 0x00],
    );
    assert_vector(
        g(GimbalCommand::ZoomRatio(ZoomRatio::new(10.0).unwrap())),
        [0x0F, 0x08, 0x03, 0xE8, 0x03, 0x00, 0x00, 0x00],
    );
    assert_vector(
        g(GimbalCommand::Photo(Photo::Single)),
        [0x0F, 0x10, 0x01, 0x00, 0x00, 0x00, 0x00, 0x00],
    );
    assert_vector(
        g(GimbalCommand::Video(Video::Start)),
        [0x0F, 0x11, 0x01, 0x00, 0x00, 0x00, 0x00, 0x00],
    );
    assert_vector(
        g(GimbalCommand::NoseFollowing),
        [0x0F, 0x02, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00],
    );
    // The look-down frame inside the protocol notes' TCP reference vector.
    assert_vector(
        g(GimbalCommand::LookDown),
        [0x0F, 0x07, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00],
    );
}

#[test]
fn gimbal_vectors() {
    use GimbalCommand as G;
    // (-1234, 10000): -1234 = 0xFB2E, 10000 = 0x2710.
    let offset = ImageOffset::new(-1234, 10000).unwrap();
    assert_vector(
        g(G::PointingZoom(offset)),
        [0x0F, 0x01, 0x2E, 0xFB, 0x10, 0x27, 0, 0],
    );
    let corner = ImageOffset::new(-10000, -10000).unwrap();
    assert_vector(
        g(G::PointingZoom(corner)),
        [0x0F, 0x01, 0xF0, 0xD8, 0xF0, 0xD8, 0, 0],
    );
    assert_vector(g(G::Recenter), [0x0F, 0x03, 0, 0, 0, 0, 0, 0]);
    // 100 deg/s right = 10000 = 0x2710; -100 deg/s down = -10000 = 0xD8F0.
    assert_vector(
        g(G::Rate(Rate::new(100.0, -100.0).unwrap())),
        [0x0F, 0x04, 0x10, 0x27, 0xF0, 0xD8, 0, 0],
    );
    // Centre (4096, 8191) = 0x1000, 0x1FFF; 160 x 48 units = 10, 3 sixteenths.
    let bx = TrackingBox::new(ImagePoint::new(4096, 8191).unwrap(), 160.0, 48.0).unwrap();
    assert_vector(
        g(G::StartTracking(bx)),
        [0x0F, 0x05, 0x00, 0x10, 0xFF, 0x1F, 0x0A, 0x03],
    );
    let max = TrackingBox::new(ImagePoint::new(0, 0).unwrap(), 4080.0, 0.0).unwrap();
    assert_vector(
        g(G::StartTracking(max)),
        [0x0F, 0x05, 0, 0, 0, 0, 0xFF, 0x00],
    );
    assert_vector(g(G::StopTracking), [0x0F, 0x06, 0, 0, 0, 0, 0, 0]);
    // 360 deg = 3600 = 0x0E10; 0 deg.
    assert_vector(
        g(G::Heading(Heading::new(360.0).unwrap())),
        [0x0F, 0x08, 0x01, 0x10, 0x0E, 0, 0, 0],
    );
    assert_vector(
        g(G::Heading(Heading::new(0.0).unwrap())),
        [0x0F, 0x08, 0x01, 0x00, 0x00, 0, 0, 0],
    );
    // -100 deg = -1000 = 0xFC18; 60 deg = 600 = 0x0258.
    assert_vector(
        g(G::Pitch(Pitch::new(-100.0).unwrap())),
        [0x0F, 0x08, 0x02, 0x18, 0xFC, 0, 0, 0],
    );
    assert_vector(
        g(G::Pitch(Pitch::new(60.0).unwrap())),
        [0x0F, 0x08, 0x02, 0x58, 0x02, 0, 0, 0],
    );
    // 1x = 100 = 0x0064; 35x = 3500 = 0x0DAC.
    assert_vector(
        g(G::ZoomRatio(ZoomRatio::new(1.0).unwrap())),
        [0x0F, 0x08, 0x03, 0x64, 0x00, 0, 0, 0],
    );
    assert_vector(
        g(G::ZoomRatio(ZoomRatio::new(35.0).unwrap())),
        [0x0F, 0x08, 0x03, 0xAC, 0x0D, 0, 0, 0],
    );
    assert_vector(
        g(G::Photo(Photo::burst(3).unwrap())),
        [0x0F, 0x10, 0x02, 0x03, 0, 0, 0, 0],
    );
    assert_vector(
        g(G::Photo(Photo::time_lapse(255).unwrap())),
        [0x0F, 0x10, 0x03, 0xFF, 0, 0, 0, 0],
    );
    assert_vector(
        g(G::Photo(Photo::timer(10).unwrap())),
        [0x0F, 0x10, 0x04, 0x0A, 0, 0, 0, 0],
    );
    assert_vector(g(G::Photo(Photo::Stop)), [0x0F, 0x10, 0x05, 0, 0, 0, 0, 0]);
    assert_vector(g(G::Video(Video::Stop)), [0x0F, 0x11, 0x02, 0, 0, 0, 0, 0]);
    for (zoom, code) in [
        (Zoom::In, 1),
        (Zoom::Out, 2),
        (Zoom::Stop, 3),
        (Zoom::Reset, 4),
        (Zoom::Double, 5),
        (Zoom::Half, 6),
    ] {
        assert_vector(g(G::Zoom(zoom)), [0x0F, 0x12, code, 0, 0, 0, 0, 0]);
    }
    for (focus, code) in [
        (Focus::Plus, 1),
        (Focus::Minus, 2),
        (Focus::Stop, 3),
        (Focus::Auto, 4),
    ] {
        assert_vector(g(G::Focus(focus)), [0x0F, 0x13, code, 0, 0, 0, 0, 0]);
    }
    // (300, 8000) = 0x012C, 0x1F40; DATA5 = DATA6 = 25 = 0x19.
    assert_vector(
        g(G::PointingFocus(ImagePoint::new(300, 8000).unwrap())),
        [0x0F, 0x14, 0x2C, 0x01, 0x40, 0x1F, 0x19, 0x19],
    );
    assert_vector(g(G::FastCalibration), [0x0F, 0xF0, 0, 0, 0, 0, 0, 0]);
}

#[test]
fn dual_light_vectors() {
    use DualLightCommand as D;
    let offset = ImageOffset::new(10000, -1).unwrap();
    assert_vector(
        d(D::PointingZoom(offset)),
        [0x1F, 0x01, 0x10, 0x27, 0xFF, 0xFF, 0, 0],
    );
    assert_vector(
        d(D::Palette(Palette::IceBlue)),
        [0x1F, 0x02, 0x0A, 0, 0, 0, 0, 0],
    );
    assert_vector(
        d(D::Palette(Palette::BlackHot)),
        [0x1F, 0x02, 0x00, 0, 0, 0, 0, 0],
    );
    assert_vector(
        d(D::Palette(Palette::ColdBlue)),
        [0x1F, 0x02, 0x0E, 0, 0, 0, 0, 0],
    );
    // Left 5 deg/s and up 5 deg/s, as on the gimbal.
    assert_vector(
        d(D::Rate(Rate::new(-5.0, 5.0).unwrap())),
        [0x1F, 0x04, 0x0C, 0xFE, 0xF4, 0x01, 0, 0],
    );
    let bx = TrackingBox::new(ImagePoint::new(1, 2).unwrap(), 16.0, 4080.0).unwrap();
    assert_vector(
        d(D::StartTracking(bx)),
        [0x1F, 0x05, 0x01, 0x00, 0x02, 0x00, 0x01, 0xFF],
    );
    assert_vector(d(D::StopTracking), [0x1F, 0x07, 0, 0, 0, 0, 0, 0]);
    for (ez, code) in [
        (ElectronicZoom::In, 1),
        (ElectronicZoom::Out, 2),
        (ElectronicZoom::Stop, 3),
    ] {
        assert_vector(d(D::ElectronicZoom(ez)), [0x1F, 0x12, code, 0, 0, 0, 0, 0]);
    }
}

#[test]
fn palettes() {
    let names = [
        "black-hot",
        "white-hot",
        "iron-red",
        "rainbow",
        "lava",
        "rainbow-enhanced",
        "molten-metal",
        "bluish-red",
        "amber",
        "amber-inverted",
        "ice-blue",
        "high-contrast",
        "grayscale-inverted",
        "hot-red",
        "cold-blue",
    ];
    for (i, (p, name)) in Palette::ALL.into_iter().zip(names).enumerate() {
        assert_eq!(usize::from(p.code()), i);
        assert_eq!(Palette::from_code(i as u8), Some(p));
        assert_eq!(p.name(), name);
        assert_eq!(Palette::from_name(name), Some(p));
        assert_eq!(std::format!("{p}"), name);
    }
    assert_eq!(Palette::IceBlue.code(), 0x0A);
    assert_eq!(Palette::HotRed.code(), 0x0D);
    assert_eq!(Palette::from_code(0x0F), None);
    assert_eq!(Palette::from_name("Ice-Blue"), None);
    assert_eq!(Palette::from_name(""), None);
}

#[test]
fn peripheral_codes() {
    assert_eq!(Peripheral::Gimbal.code(), 0x0F);
    assert_eq!(Peripheral::DualLight.code(), 0x1F);
    for code in 0..=u8::MAX {
        let p = Peripheral::from_code(code);
        assert_eq!(p.is_some(), code == 0x0F || code == 0x1F);
        if let Some(p) = p {
            assert_eq!(p.code(), code);
        }
    }
    assert_eq!(g(GimbalCommand::Recenter).peripheral(), Peripheral::Gimbal);
    assert_eq!(
        d(DualLightCommand::StopTracking).peripheral(),
        Peripheral::DualLight
    );
    assert_eq!(Command::ID, ids::CONTROL);
}

#[test]
fn is_pointing() {
    use DualLightCommand as D;
    use GimbalCommand as G;
    let o = ImageOffset::CENTRE;
    let p = ImagePoint::new(0, 0).unwrap();
    let bx = TrackingBox::from_raw(p, 1, 1);
    let pointing = [
        g(G::PointingZoom(o)),
        g(G::NoseFollowing),
        g(G::Recenter),
        g(G::Rate(Rate::ZERO)),
        g(G::StartTracking(bx)),
        g(G::LookDown),
        g(G::Heading(Heading::from_deci(0).unwrap())),
        g(G::Pitch(Pitch::from_deci(0).unwrap())),
        d(D::PointingZoom(o)),
        d(D::Rate(Rate::ZERO)),
        d(D::StartTracking(bx)),
    ];
    let other = [
        g(G::StopTracking),
        g(G::ZoomRatio(ZoomRatio::from_centi(100).unwrap())),
        g(G::Photo(Photo::Single)),
        g(G::Video(Video::Start)),
        g(G::Zoom(Zoom::In)),
        g(G::Focus(Focus::Auto)),
        g(G::PointingFocus(p)),
        g(G::FastCalibration),
        d(D::Palette(Palette::Lava)),
        d(D::StopTracking),
        d(D::ElectronicZoom(ElectronicZoom::In)),
    ];
    for c in pointing {
        assert!(c.is_pointing(), "{c:?}");
    }
    for c in other {
        assert!(!c.is_pointing(), "{c:?}");
    }
}

#[test]
fn rejections() {
    let err = |b: &[u8]| Command::decode(b).unwrap_err();
    let unknown_peripheral = [0x2F, 0x02, 0, 0, 0, 0, 0, 0];
    assert_eq!(
        err(&unknown_peripheral),
        DecodeError::UnknownPeripheral {
            data: unknown_peripheral
        }
    );
    for bytes in [
        [0x0F, 0x09, 0, 0, 0, 0, 0, 0],
        [0x0F, 0x00, 0, 0, 0, 0, 0, 0],
        [0x0F, 0xFF, 0, 0, 0, 0, 0, 0],
        // Stop tracking is 0x07 on the dual-light camera; 0x06 is nothing there.
        [0x1F, 0x06, 0, 0, 0, 0, 0, 0],
        [0x1F, 0x03, 0, 0, 0, 0, 0, 0],
        [0x1F, 0x10, 0x01, 0, 0, 0, 0, 0],
        [0x1F, 0xF0, 0, 0, 0, 0, 0, 0],
    ] {
        assert_eq!(err(&bytes), DecodeError::UnknownCommand { data: bytes });
    }
    for bytes in [
        [0x0F, 0x02, 0x01, 0, 0, 0, 0, 0],
        [0x0F, 0x07, 0, 0, 0, 0, 0, 0x01],
        [0x1F, 0x07, 0, 0, 0, 0, 0x80, 0],
        [0x0F, 0x04, 0x0C, 0xFE, 0, 0, 0x01, 0],
        [0x0F, 0x08, 0x01, 0xC2, 0x01, 0x01, 0, 0],
        [0x0F, 0x10, 0x01, 0x03, 0, 0, 0, 0],
        [0x0F, 0x10, 0x02, 0x03, 0x01, 0, 0, 0],
        [0x0F, 0x11, 0x01, 0, 0, 0, 0, 0xFF],
        [0x1F, 0x02, 0x0A, 0x01, 0, 0, 0, 0],
        [0x1F, 0x12, 0x01, 0, 0, 0x01, 0, 0],
        [0x0F, 0x01, 0, 0, 0, 0, 0x01, 0],
    ] {
        assert_eq!(err(&bytes), DecodeError::NonZeroPadding { data: bytes });
    }
    let invalid = |bytes: [u8; 8], field: &'static str| {
        assert_eq!(
            err(&bytes),
            DecodeError::InvalidValue { data: bytes, field },
            "{bytes:02X?}"
        );
    };
    // Heading 3601, pitch 601 and -1001, zoom 99 and 3501, angle types 0, 4, 7.
    invalid([0x0F, 0x08, 0x01, 0x11, 0x0E, 0, 0, 0], "heading");
    invalid([0x0F, 0x08, 0x01, 0xFF, 0xFF, 0, 0, 0], "heading");
    invalid([0x0F, 0x08, 0x02, 0x59, 0x02, 0, 0, 0], "pitch");
    invalid([0x0F, 0x08, 0x02, 0x17, 0xFC, 0, 0, 0], "pitch");
    invalid([0x0F, 0x08, 0x03, 0x63, 0x00, 0, 0, 0], "zoom_ratio");
    invalid([0x0F, 0x08, 0x03, 0xAD, 0x0D, 0, 0, 0], "zoom_ratio");
    invalid([0x0F, 0x08, 0x00, 0, 0, 0, 0, 0], "angle_type");
    invalid([0x0F, 0x08, 0x04, 0x64, 0, 0, 0, 0], "angle_type");
    invalid([0x0F, 0x08, 0x07, 0, 0, 0, 0, 0], "angle_type");
    // Rates 10001 and -10001.
    invalid([0x0F, 0x04, 0x11, 0x27, 0, 0, 0, 0], "yaw_rate");
    invalid([0x1F, 0x04, 0, 0, 0xEF, 0xD8, 0, 0], "pitch_rate");
    // Offsets 10001, -10001 and i16::MIN.
    invalid([0x0F, 0x01, 0x11, 0x27, 0, 0, 0, 0], "x");
    invalid([0x1F, 0x01, 0, 0, 0xEF, 0xD8, 0, 0], "y");
    invalid([0x0F, 0x01, 0x00, 0x80, 0, 0, 0, 0], "x");
    // Image points 8192.
    invalid([0x0F, 0x05, 0x00, 0x20, 0, 0, 1, 1], "x");
    invalid([0x1F, 0x05, 0, 0, 0x00, 0x20, 1, 1], "y");
    invalid([0x0F, 0x14, 0x00, 0x20, 0, 0, 25, 25], "x");
    // Pointing focus must carry 25, 25.
    invalid([0x0F, 0x14, 0, 0, 0, 0, 0, 0], "focus_box");
    invalid([0x0F, 0x14, 0, 0, 0, 0, 25, 24], "focus_box");
    invalid([0x0F, 0x14, 0, 0, 0, 0, 26, 25], "focus_box");
    // Photo: unknown modes and zero parameters.
    invalid([0x0F, 0x10, 0x09, 0, 0, 0, 0, 0], "photo_mode");
    invalid([0x0F, 0x10, 0x00, 0, 0, 0, 0, 0], "photo_mode");
    invalid([0x0F, 0x10, 0x06, 0x01, 0, 0, 0, 0], "photo_mode");
    invalid([0x0F, 0x10, 0x02, 0x00, 0, 0, 0, 0], "count");
    invalid([0x0F, 0x10, 0x03, 0x00, 0, 0, 0, 0], "seconds");
    invalid([0x0F, 0x10, 0x04, 0x00, 0, 0, 0, 0], "seconds");
    // Sub-codes one past the end, and zero.
    invalid([0x0F, 0x11, 0x03, 0, 0, 0, 0, 0], "video_mode");
    invalid([0x0F, 0x11, 0x00, 0, 0, 0, 0, 0], "video_mode");
    invalid([0x0F, 0x12, 0x07, 0, 0, 0, 0, 0], "zoom_mode");
    invalid([0x0F, 0x12, 0x00, 0, 0, 0, 0, 0], "zoom_mode");
    invalid([0x0F, 0x13, 0x05, 0, 0, 0, 0, 0], "focus_mode");
    invalid([0x1F, 0x12, 0x04, 0, 0, 0, 0, 0], "electronic_zoom_mode");
    invalid([0x1F, 0x02, 0x0F, 0, 0, 0, 0, 0], "palette");
    // An invalid value is reported before non-zero padding.
    invalid([0x0F, 0x08, 0x07, 0, 0, 0, 0, 0xFF], "angle_type");

    let ok = [0x0F, 0x07, 0, 0, 0, 0, 0, 0];
    assert_eq!(err(&ok[..7]), DecodeError::WrongLength { len: 7 });
    assert_eq!(
        err(&[0x0F, 0x07, 0, 0, 0, 0, 0, 0, 0]),
        DecodeError::WrongLength { len: 9 }
    );
    assert_eq!(err(&[]), DecodeError::WrongLength { len: 0 });
    assert!(Command::decode(&ok).is_ok());
}

#[test]
fn decode_error_display_and_data() {
    let e = DecodeError::InvalidValue {
        data: [0x0F, 0x10, 0x09, 0, 0, 0, 0, 0],
        field: "photo_mode",
    };
    assert_eq!(
        std::format!("{e}"),
        "control frame [0F, 10, 09, 00, 00, 00, 00, 00]: invalid photo_mode"
    );
    assert_eq!(e.data(), Some(&[0x0F, 0x10, 0x09, 0, 0, 0, 0, 0]));
    let e = DecodeError::WrongLength { len: 7 };
    assert_eq!(std::format!("{e}"), "control frame must be 8 bytes, got 7");
    assert_eq!(e.data(), None);
}

#[test]
fn rounding_to_nearest() {
    // Binary-exact halves round away from zero.
    assert_eq!(Pitch::new(-0.25).unwrap().deci(), -3);
    assert_eq!(Pitch::new(0.25).unwrap().deci(), 3);
    assert_eq!(Heading::new(0.25).unwrap().deci(), 3);
    assert_eq!(ZoomRatio::new(1.125).unwrap().centi(), 113);
    let r = Rate::new(0.125, -0.125).unwrap();
    assert_eq!((r.yaw_centi(), r.pitch_centi()), (13, -13));
    // Values well clear of a half in f32.
    assert_eq!(Pitch::new(-45.04).unwrap().deci(), -450);
    assert_eq!(Pitch::new(-45.06).unwrap().deci(), -451);
    assert_eq!(Heading::new(45.04).unwrap().deci(), 450);
    assert_eq!(Heading::new(45.06).unwrap().deci(), 451);
    assert_eq!(Heading::new(359.96).unwrap().deci(), 3600);
    // The range check is on the physical value, before rounding.
    assert_rejects(Pitch::new(60.04), "pitch");
    assert_eq!(Pitch::new(59.96).unwrap().deci(), 600);
    assert_eq!(ZoomRatio::new(10.004).unwrap().centi(), 1000);
    assert_eq!(ZoomRatio::new(10.006).unwrap().centi(), 1001);
    let r = Rate::new(-5.0, 12.345_6).unwrap();
    assert_eq!((r.yaw_centi(), r.pitch_centi()), (-500, 1235));
    // Tracking box sides: nearest multiple of 16, halves up.
    let c = ImagePoint::new(0, 0).unwrap();
    let bx = TrackingBox::new(c, 8.0, 23.9).unwrap();
    assert_eq!((bx.width16(), bx.height16()), (1, 1));
    let bx = TrackingBox::new(c, 7.9, 24.0).unwrap();
    assert_eq!((bx.width16(), bx.height16()), (0, 2));
    assert_eq!((bx.width(), bx.height()), (0, 32));
    let bx = TrackingBox::new(c, 4079.9, 4072.0).unwrap();
    assert_eq!((bx.width16(), bx.height16()), (255, 255));
    assert_eq!((bx.width(), bx.height()), (4080, 4080));
}

#[test]
fn accessors() {
    let r = Rate::new(-5.0, 0.5).unwrap();
    assert_eq!((r.yaw_dps(), r.pitch_dps()), (-5.0, 0.5));
    assert!(!r.is_zero());
    assert!(Rate::ZERO.is_zero());
    assert_eq!(Rate::new(0.004, -0.004).unwrap(), Rate::ZERO);
    assert_eq!(Rate::from_centi(-500, 50).unwrap(), r);
    assert_eq!(Heading::from_deci(450).unwrap().degrees(), 45.0);
    assert_eq!(Pitch::from_deci(-450).unwrap().degrees(), -45.0);
    assert_eq!(ZoomRatio::from_centi(1000).unwrap().ratio(), 10.0);
    let o = ImageOffset::new(-3, 4).unwrap();
    assert_eq!((o.x(), o.y()), (-3, 4));
    let p = ImagePoint::new(8191, 7).unwrap();
    assert_eq!((p.x(), p.y()), (8191, 7));
    let bx = TrackingBox::from_raw(p, 2, 3);
    assert_eq!(bx.centre(), p);
    assert_eq!((bx.width(), bx.height()), (32, 48));
    assert_eq!(Photo::burst(3).unwrap(), Photo::Burst(nz(3)));
    assert_eq!(Photo::time_lapse(1).unwrap(), Photo::TimeLapse(nz(1)));
    assert_eq!(Photo::timer(255).unwrap(), Photo::Timer(nz(255)));
    assert_eq!(
        Command::from(GimbalCommand::LookDown),
        Command::Gimbal(GimbalCommand::LookDown)
    );
    assert_eq!(
        Command::from(DualLightCommand::StopTracking),
        Command::DualLight(DualLightCommand::StopTracking)
    );
}

#[track_caller]
fn assert_rejects<T: fmt::Debug>(r: Result<T, RangeError>, field: &str) {
    match r {
        Err(e) => assert_eq!(e.field, field),
        Ok(v) => panic!("{field}: accepted {v:?}"),
    }
}

#[test]
fn constructors_bounds() {
    let bad = [f32::NAN, f32::INFINITY, f32::NEG_INFINITY];
    // Each f32 constructor: (accepts?, inclusive bounds, just-outside values).
    for v in bad.into_iter().chain([60.06, -100.06, 60.01, -100.01]) {
        assert_rejects(Pitch::new(v), "pitch");
    }
    assert_eq!(Pitch::new(60.0).unwrap().deci(), 600);
    assert_eq!(Pitch::new(-100.0).unwrap().deci(), -1000);
    for v in bad.into_iter().chain([360.01, -0.01, 360.06]) {
        assert_rejects(Heading::new(v), "heading");
    }
    assert_eq!(Heading::new(360.0).unwrap().deci(), 3600);
    assert_eq!(Heading::new(-0.0).unwrap().deci(), 0);
    for v in bad.into_iter().chain([0.99, 35.01, 0.0, -1.0]) {
        assert_rejects(ZoomRatio::new(v), "zoom_ratio");
    }
    assert_eq!(ZoomRatio::new(1.0).unwrap().centi(), 100);
    assert_eq!(ZoomRatio::new(35.0).unwrap().centi(), 3500);
    for v in bad.into_iter().chain([100.01, -100.01]) {
        assert_rejects(Rate::new(v, 0.0), "yaw_rate");
        assert_rejects(Rate::new(0.0, v), "pitch_rate");
    }
    let r = Rate::new(100.0, -100.0).unwrap();
    assert_eq!((r.yaw_centi(), r.pitch_centi()), (10000, -10000));
    let r = Rate::new(-100.0, 100.0).unwrap();
    assert_eq!((r.yaw_centi(), r.pitch_centi()), (-10000, 10000));
    let c = ImagePoint::new(0, 0).unwrap();
    for v in bad.into_iter().chain([4080.01, -0.01, 4088.0]) {
        assert_rejects(TrackingBox::new(c, v, 0.0), "width");
        assert_rejects(TrackingBox::new(c, 0.0, v), "height");
    }
    assert!(TrackingBox::new(c, 4080.0, 4080.0).is_ok());
    assert!(TrackingBox::new(c, 0.0, 0.0).is_ok());

    // Wire-unit constructors.
    for v in [10001, -10001, i16::MIN, i16::MAX] {
        assert_rejects(Rate::from_centi(v, 0), "yaw_rate");
        assert_rejects(Rate::from_centi(0, v), "pitch_rate");
    }
    assert!(Rate::from_centi(10000, -10000).is_ok());
    assert_rejects(Heading::from_deci(3601), "heading");
    assert!(Heading::from_deci(3600).is_ok());
    assert_rejects(Pitch::from_deci(601), "pitch");
    assert_rejects(Pitch::from_deci(-1001), "pitch");
    assert!(Pitch::from_deci(600).is_ok() && Pitch::from_deci(-1000).is_ok());
    assert_rejects(ZoomRatio::from_centi(99), "zoom_ratio");
    assert_rejects(ZoomRatio::from_centi(3501), "zoom_ratio");
    assert!(ZoomRatio::from_centi(100).is_ok() && ZoomRatio::from_centi(3500).is_ok());

    // Integer constructors.
    for v in [10001, -10001, i32::MIN, i32::MAX] {
        assert_rejects(ImageOffset::new(v, 0), "x");
        assert_rejects(ImageOffset::new(0, v), "y");
    }
    assert!(ImageOffset::new(10000, -10000).is_ok());
    assert!(ImageOffset::new(-10000, 10000).is_ok());
    for v in [-1, 8192, i32::MIN, i32::MAX] {
        assert_rejects(ImagePoint::new(v, 0), "x");
        assert_rejects(ImagePoint::new(0, v), "y");
    }
    assert!(ImagePoint::new(8191, 0).is_ok() && ImagePoint::new(0, 8191).is_ok());
    for v in [0, 256, u32::MAX] {
        assert_rejects(Photo::burst(v), "count");
        assert_rejects(Photo::time_lapse(v), "seconds");
        assert_rejects(Photo::timer(v), "seconds");
    }
    for v in [1, 255] {
        assert!(Photo::burst(v).is_ok());
        assert!(Photo::time_lapse(v).is_ok());
        assert!(Photo::timer(v).is_ok());
    }
}

#[test]
fn range_errors_are_in_physical_units() {
    let e = Pitch::from_deci(601).unwrap_err();
    assert_eq!((e.field, e.min, e.max), ("pitch", -100.0, 60.0));
    assert!((e.value - 60.1).abs() < 1e-9);
    let e = Rate::from_centi(0, -10001).unwrap_err();
    assert_eq!(
        (e.field, e.value, e.min, e.max),
        ("pitch_rate", -100.01, -100.0, 100.0)
    );
    let e = Photo::burst(0).unwrap_err();
    assert_eq!((e.field, e.value, e.min, e.max), ("count", 0.0, 1.0, 255.0));
    let e = Pitch::new(f32::NAN).unwrap_err();
    assert!(e.is_not_finite());
}

fn arb_rate() -> impl Strategy<Value = Rate> {
    (-10000i16..=10000, -10000i16..=10000).prop_map(|(y, p)| Rate::from_centi(y, p).unwrap())
}

fn arb_offset() -> impl Strategy<Value = ImageOffset> {
    (-10000i32..=10000, -10000i32..=10000).prop_map(|(x, y)| ImageOffset::new(x, y).unwrap())
}

fn arb_point() -> impl Strategy<Value = ImagePoint> {
    (0i32..=8191, 0i32..=8191).prop_map(|(x, y)| ImagePoint::new(x, y).unwrap())
}

fn arb_box() -> impl Strategy<Value = TrackingBox> {
    (arb_point(), any::<u8>(), any::<u8>()).prop_map(|(c, w, h)| TrackingBox::from_raw(c, w, h))
}

fn arb_photo() -> impl Strategy<Value = Photo> {
    prop_oneof![
        Just(Photo::Single),
        Just(Photo::Stop),
        (1u32..=255).prop_map(|n| Photo::burst(n).unwrap()),
        (1u32..=255).prop_map(|n| Photo::time_lapse(n).unwrap()),
        (1u32..=255).prop_map(|n| Photo::timer(n).unwrap()),
    ]
}

fn arb_gimbal() -> impl Strategy<Value = GimbalCommand> {
    use GimbalCommand as G;
    prop_oneof![
        arb_offset().prop_map(G::PointingZoom),
        Just(G::NoseFollowing),
        Just(G::Recenter),
        arb_rate().prop_map(G::Rate),
        arb_box().prop_map(G::StartTracking),
        Just(G::StopTracking),
        Just(G::LookDown),
        (0u16..=3600).prop_map(|v| G::Heading(Heading::from_deci(v).unwrap())),
        (-1000i16..=600).prop_map(|v| G::Pitch(Pitch::from_deci(v).unwrap())),
        (100u16..=3500).prop_map(|v| G::ZoomRatio(ZoomRatio::from_centi(v).unwrap())),
        arb_photo().prop_map(G::Photo),
        prop::sample::select(&[Video::Start, Video::Stop][..]).prop_map(G::Video),
        prop::sample::select(
            &[
                Zoom::In,
                Zoom::Out,
                Zoom::Stop,
                Zoom::Reset,
                Zoom::Double,
                Zoom::Half
            ][..]
        )
        .prop_map(G::Zoom),
        prop::sample::select(&[Focus::Plus, Focus::Minus, Focus::Stop, Focus::Auto][..])
            .prop_map(G::Focus),
        arb_point().prop_map(G::PointingFocus),
        Just(G::FastCalibration),
    ]
}

fn arb_dual_light() -> impl Strategy<Value = DualLightCommand> {
    use DualLightCommand as D;
    prop_oneof![
        arb_offset().prop_map(D::PointingZoom),
        prop::sample::select(&Palette::ALL[..]).prop_map(D::Palette),
        arb_rate().prop_map(D::Rate),
        arb_box().prop_map(D::StartTracking),
        Just(D::StopTracking),
        prop::sample::select(
            &[
                ElectronicZoom::In,
                ElectronicZoom::Out,
                ElectronicZoom::Stop
            ][..]
        )
        .prop_map(D::ElectronicZoom),
    ]
}

fn arb_command() -> impl Strategy<Value = Command> {
    prop_oneof![
        arb_gimbal().prop_map(Command::Gimbal),
        arb_dual_light().prop_map(Command::DualLight),
    ]
}

/// Frames biased towards valid ones: known peripherals and commands, small sub-codes,
/// zero bytes, and the bytes of real commands with one byte changed.
fn arb_frame() -> impl Strategy<Value = [u8; 8]> {
    let byte = prop_oneof![3 => Just(0u8), 2 => 0u8..8, 1 => Just(25u8), 2 => any::<u8>()];
    let cmd = prop_oneof![
        prop::sample::select(
            &[
                0x01u8, 0x02, 0x03, 0x04, 0x05, 0x06, 0x07, 0x08, 0x10, 0x11, 0x12, 0x13, 0x14,
                0xF0
            ][..]
        ),
        any::<u8>(),
    ];
    let peripheral = prop_oneof![4 => Just(0x0Fu8), 4 => Just(0x1F), 1 => any::<u8>()];
    let built = (
        peripheral,
        cmd,
        [
            byte.clone(),
            byte.clone(),
            byte.clone(),
            byte.clone(),
            byte.clone(),
            byte,
        ],
    )
        .prop_map(|(p, c, [d1, d2, d3, d4, d5, d6])| [p, c, d1, d2, d3, d4, d5, d6]);
    let mutated = (arb_command(), 0usize..8, any::<u8>()).prop_map(|(c, i, b)| {
        let mut bytes = c.encode();
        bytes[i] = b;
        bytes
    });
    prop_oneof![built, mutated]
}

proptest! {
    /// `encode`'s constant-and-or path for the angle commands writes what the field
    /// writer does, for every command.
    #[test]
    fn encode_equals_the_field_writer(cmd in arb_command()) {
        prop_assert_eq!(cmd.encode(), cmd.encode_fields().to_le_bytes());
    }

    #[test]
    fn encode_decode_round_trip(cmd in arb_command()) {
        let bytes = cmd.encode();
        prop_assert_eq!(bytes[0], cmd.peripheral().code());
        prop_assert_eq!(Command::decode(&bytes), Ok(cmd));
        prop_assert_eq!(cmd.to_frame(), Frame::new(0x0F01, bytes));
    }

    #[test]
    fn decode_encode_round_trip(bytes in arb_frame()) {
        if let Ok(cmd) = Command::decode(&bytes) {
            prop_assert_eq!(cmd.encode(), bytes);
        }
    }

    #[test]
    fn decode_any_bytes_never_panics(bytes in proptest::collection::vec(any::<u8>(), 0..16)) {
        match Command::decode(&bytes) {
            Err(DecodeError::WrongLength { len }) => {
                prop_assert_eq!(len, bytes.len());
                prop_assert_ne!(len, 8);
            }
            Err(e) => {
                prop_assert_eq!(bytes.len(), 8);
                prop_assert_eq!(e.data().map(|d| &d[..]), Some(&bytes[..]));
            }
            Ok(cmd) => prop_assert_eq!(&cmd.encode()[..], &bytes[..]),
        }
    }

    // Each value on the wire is the nearest step: within half a step of the angle or ratio
    // given, plus `f32`'s rounding of the scaled value (below 1e-4 at these magnitudes). Any `f32`, and as
    // often one in and around the range, so that its ends are drawn.
    #[test]
    fn pitch_accepts_exactly_its_range(v in prop_oneof![any::<f32>(), -100.5f32..60.5]) {
        let r = Pitch::new(v);
        prop_assert_eq!(r.is_ok(), (-100.0..=60.0).contains(&v));
        if let Ok(p) = r {
            prop_assert!((f32::from(p.deci()) / 10.0 - v).abs() <= 0.05 + 1e-4, "{} {}", v, p.deci());
        }
    }

    #[test]
    fn heading_accepts_exactly_its_range(v in prop_oneof![any::<f32>(), -0.5f32..360.5]) {
        let r = Heading::new(v);
        prop_assert_eq!(r.is_ok(), (0.0..=360.0).contains(&v));
        if let Ok(h) = r {
            prop_assert!((f32::from(h.deci()) / 10.0 - v).abs() <= 0.05 + 1e-4, "{} {}", v, h.deci());
        }
    }

    #[test]
    fn zoom_ratio_accepts_exactly_its_range(v in prop_oneof![any::<f32>(), 0.5f32..35.5]) {
        let r = ZoomRatio::new(v);
        prop_assert_eq!(r.is_ok(), (1.0..=35.0).contains(&v));
        if let Ok(z) = r {
            prop_assert!((f32::from(z.centi()) / 100.0 - v).abs() <= 0.005 + 1e-4, "{} {}", v, z.centi());
        }
    }

    #[test]
    fn rate_accepts_exactly_its_range(
        y in prop_oneof![any::<f32>(), -100.5f32..100.5],
        p in -100.0f32..=100.0,
    ) {
        let r = Rate::new(y, p);
        prop_assert_eq!(r.is_ok(), (-100.0..=100.0).contains(&y));
        if let Ok(r) = r {
            prop_assert!((f32::from(r.yaw_centi()) / 100.0 - y).abs() <= 0.005 + 1e-4, "{} {}", y, r.yaw_centi());
            prop_assert!((f32::from(r.pitch_centi()) / 100.0 - p).abs() <= 0.005 + 1e-4, "{} {}", p, r.pitch_centi());
        }
    }

    #[test]
    fn tracking_box_accepts_exactly_its_range(w in any::<f32>(), h in 0.0f32..=4080.0) {
        let c = ImagePoint::new(1, 1).unwrap();
        let r = TrackingBox::new(c, w, h);
        prop_assert_eq!(r.is_ok(), (0.0..=4080.0).contains(&w));
        if let Ok(b) = r {
            prop_assert!((f32::from(b.width()) - w).abs() <= 8.0);
            prop_assert!((f32::from(b.height()) - h).abs() <= 8.0);
        }
    }

    #[test]
    fn integer_constructors_accept_exactly_their_range(x in any::<i32>(), n in any::<u32>()) {
        prop_assert_eq!(ImageOffset::new(x, 0).is_ok(), (-10000..=10000).contains(&x));
        prop_assert_eq!(ImagePoint::new(0, x).is_ok(), (0..=8191).contains(&x));
        prop_assert_eq!(Photo::burst(n).is_ok(), (1..=255).contains(&n));
        prop_assert_eq!(Photo::timer(n).is_ok(), (1..=255).contains(&n));
    }

    #[test]
    fn physical_accessors_round_trip(h in 0u16..=3600, p in -1000i16..=600, z in 100u16..=3500, y in -10000i16..=10000) {
        let h = Heading::from_deci(h).unwrap();
        prop_assert_eq!(Heading::new(h.degrees()), Ok(h));
        let p = Pitch::from_deci(p).unwrap();
        prop_assert_eq!(Pitch::new(p.degrees()), Ok(p));
        let z = ZoomRatio::from_centi(z).unwrap();
        prop_assert_eq!(ZoomRatio::new(z.ratio()), Ok(z));
        let r = Rate::from_centi(y, -y).unwrap();
        prop_assert_eq!(Rate::new(r.yaw_dps(), r.pitch_dps()), Ok(r));
    }
}
