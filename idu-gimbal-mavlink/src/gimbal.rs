//! The gimbal side of the bridge: the core's command surface, on either transport.
//!
//! The bridge drives anything that implements the core's [`GimbalControl`]: the sans-IO
//! links ([`Link`](idu_gimbal::link::Link) on CAN,
//! [`SerialLink`](idu_gimbal::link::serial::SerialLink) on the UART) and the drivers over
//! them ([`Gimbal`](idu_gimbal::Gimbal), [`SerialGimbal`](idu_gimbal::SerialGimbal)); the
//! application keeps polling the driver as usual. Where the transport carries no vehicle
//! frames (the UART), the vehicle's data is kept for point-at and headings stay
//! nose-referenced, which the status and the setpoint conversion read from
//! [`GimbalControl::north_referenced`].

pub use idu_gimbal::GimbalControl;
