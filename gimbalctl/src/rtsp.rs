//! `gimbalctl rtsp FAMILY STREAM [--ip IP] [--user U --password P]`.

use std::net::Ipv4Addr;

use idu_gimbal::video::{Camera, Credentials, Family, Stream, VideoError};

use crate::error::Failure;

/// The stream's RTSP address; every error is a usage error (exit 2).
pub fn address(
    family: &str,
    stream: &str,
    ip: Option<Ipv4Addr>,
    credentials: Option<(&str, &str)>,
) -> Result<String, Failure> {
    let usage = |e: VideoError| Failure::Usage(format!("rtsp: {e}"));
    let named = |name: &str, e: VideoError| Failure::Usage(format!("rtsp: {name:?}: {e}"));
    let family = Family::from_name(family).map_err(|e| named(family, e))?;
    let stream = Stream::from_name(stream).map_err(|e| named(stream, e))?;
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
