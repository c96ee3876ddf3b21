//! `gimbalctl rtsp FAMILY STREAM [--ip IP] [--user U --password P]`.

use std::net::Ipv4Addr;

use idu_gimbal::video::{Camera, Credentials, Family, Stream};

use crate::error::Failure;

/// The stream's RTSP address; every error is a usage error (exit 2).
pub fn address(
    family: &str,
    stream: &str,
    ip: Option<Ipv4Addr>,
    credentials: Option<(&str, &str)>,
) -> Result<String, Failure> {
    let usage = |e: idu_gimbal::video::VideoError| Failure::Usage(format!("rtsp: {e}"));
    let family = Family::from_name(family).map_err(usage)?;
    let stream = Stream::from_name(stream).map_err(usage)?;
    let mut camera = Camera::new(family);
    if let Some(ip) = ip {
        camera = camera.with_ip(ip);
    }
    let url = match credentials {
        Some((user, password)) => camera
            .with_credentials(Credentials::new(user, password))
            .url(stream),
        None => camera.url(stream),
    }
    .map_err(usage)?;
    Ok(url.as_str().to_owned())
}
