//! RTSP addresses of the gimbal cameras' video streams (section 1.3), without allocation.
//!
//! | family | stream | address |
//! |---|---|---|
//! | [`A2000`](Family::A2000) | main | `rtsp://IP:554/live` |
//! | [`X3`](Family::X3), [`Argus`](Family::Argus) | main, aux1, aux2 | `rtsp://USER:PASS@IP:554/cam/realmonitor?channel=1&subtype=0` (`1`, `2`) |
//! | [`DualLight`](Family::DualLight) | main, aux1, infrared | `rtsp://USER:PASS@IP:554/cam/realmonitor?channel=1&subtype=0` (`1`, `2`) |
//! | [`F10`](Family::F10) | main | `rtsp://IP:554/ch1/sub/av_stream` |
//!
//! `IP` defaults to [`DEFAULT_IP`] (192.168.42.108) and `USER:PASS` to
//! [`Credentials::DEFAULT`] (`admin:admin`); both can be overridden. The A2000 and F10
//! addresses carry no credentials, so those families ignore them.
//!
//! Notes on the document:
//! - Its A2000 cell is garbled (`rtsp: //<IP>: live 554/`); its own example in the same
//!   cell, `rtsp://192.168.42.108:554/live`, gives the form used here.
//! - The postback's "gimbal type" byte (X30, X30T, A2000, dual light, ...) is **not**
//!   mapped to a stream family anywhere in the document, so this crate does not guess
//!   one: the user has to say which family the camera is (e.g. a `--family` option).
//!
//! # Credentials
//!
//! The user name and password go into the URL's userinfo (RFC 3986, section 3.2.1). Every
//! byte of them that is not an RFC 3986 *unreserved* character (`A-Z a-z 0-9 - . _ ~`) is
//! percent-encoded, as UTF-8: that covers `@ : / ? # [ ] %`, space, control characters and
//! non-ASCII, so the address is always a well-formed URL, and RTSP clients decode it back
//! to the original text. Each of the two may be at most [`Credentials::MAX_LEN`] bytes
//! (UTF-8), which keeps the longest address within [`URL_CAPACITY`].
//!
//! The address contains the password in clear (it is part of the URL); the [`Debug`]
//! output of [`Credentials`] does not.
//!
//! # Examples
//!
//! ```
//! use core::net::Ipv4Addr;
//! use idu_gimbal::video::{Camera, Credentials, Family, Stream, VideoError};
//!
//! // Defaults: 192.168.42.108, admin:admin.
//! let cam = Camera::new(Family::X3);
//! let url = cam.url(Stream::Aux1)?;
//! assert_eq!(
//!     url.as_str(),
//!     "rtsp://admin:admin@192.168.42.108:554/cam/realmonitor?channel=1&subtype=1"
//! );
//!
//! // Custom address and credentials; reserved characters are percent-encoded.
//! let cam = Camera::new(Family::DualLight)
//!     .with_ip(Ipv4Addr::new(10, 0, 0, 7))
//!     .with_credentials(Credentials::new("pilot", "p@ss:word"));
//! assert_eq!(
//!     cam.url(Stream::Infrared)?.as_str(),
//!     "rtsp://pilot:p%40ss%3Aword@10.0.0.7:554/cam/realmonitor?channel=1&subtype=2"
//! );
//!
//! // Streams a family does not have are errors that say what there is.
//! let err = Camera::new(Family::A2000).url(Stream::Aux1).unwrap_err();
//! assert_eq!(err, VideoError::NoSuchStream { family: Family::A2000, stream: Stream::Aux1 });
//! assert_eq!(err.to_string(), "a2000 has no aux1 stream; it has: main");
//!
//! // Names as a command line spells them.
//! let family: Family = "dual-light".parse()?;
//! assert_eq!(family.streams(), &[Stream::Main, Stream::Aux1, Stream::Infrared]);
//! # Ok::<(), VideoError>(())
//! ```
//!
//! Writing into any [`core::fmt::Write`], such as a fixed buffer on a microcontroller:
//!
//! ```
//! use core::fmt::Write;
//! use idu_gimbal::video::{Camera, Family, Stream, VideoError};
//!
//! let mut out: heapless::String<64> = heapless::String::new();
//! Camera::new(Family::F10).write_url(Stream::Main, &mut out)?;
//! assert_eq!(out.as_str(), "rtsp://192.168.42.108:554/ch1/sub/av_stream");
//!
//! let mut small: heapless::String<16> = heapless::String::new();
//! let err = Camera::new(Family::F10).write_url(Stream::Main, &mut small).unwrap_err();
//! assert_eq!(err, VideoError::DoesNotFit { len: 43 });
//! # Ok::<(), VideoError>(())
//! ```

use core::fmt;
use core::net::Ipv4Addr;
use core::str::FromStr;

use percent_encoding::{utf8_percent_encode, AsciiSet, NON_ALPHANUMERIC};

use crate::interface;

/// The camera's default IP address (section 1.2): [`interface::CAMERA_IP`].
pub const DEFAULT_IP: Ipv4Addr = interface::CAMERA_IP;

/// The capacity of the string [`Camera::url`] returns: 256 bytes.
///
/// It is the longest address there can be: the `realmonitor` form (64 bytes with
/// empty credentials and the widest IP, `255.255.255.255`) plus a user name and a password
/// of [`Credentials::MAX_LEN`] bytes each, every byte percent-encoded to three
/// (64 + 2 × 3 × 32 = 256).
pub const URL_CAPACITY: usize = "rtsp://".len()
    + 3 * Credentials::MAX_LEN
    + ":".len()
    + 3 * Credentials::MAX_LEN
    + "@".len()
    + "255.255.255.255".len()
    + ":554".len()
    + "/cam/realmonitor?channel=1&subtype=0".len();
const _: () = assert!(interface::RTSP_PORT == 554);

/// Bytes left as they are in the userinfo: RFC 3986 unreserved characters. Everything
/// else, including all non-ASCII bytes, is percent-encoded.
const USERINFO: &AsciiSet = &NON_ALPHANUMERIC
    .remove(b'-')
    .remove(b'.')
    .remove(b'_')
    .remove(b'~');

/// A camera family of section 1.3: decides the form of its stream addresses and which
/// streams it has.
///
/// The document gives no mapping from the postback's gimbal type to a family; see the
/// [module docs](self).
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Family {
    /// A2000: one stream, `rtsp://IP:554/live`.
    A2000,
    /// X3 series: main, aux1, aux2 at `.../cam/realmonitor?channel=1&subtype=0|1|2`.
    X3,
    /// Argus series: the same addresses as [`Family::X3`].
    Argus,
    /// Dual-light series: main, aux1 and infrared at `subtype=0|1|2`.
    DualLight,
    /// F10: one stream, `rtsp://IP:554/ch1/sub/av_stream`.
    F10,
}

impl Family {
    /// Every family, in the document's order.
    pub const ALL: [Family; 5] = [
        Family::A2000,
        Family::X3,
        Family::Argus,
        Family::DualLight,
        Family::F10,
    ];

    /// The family's command-line name: `a2000`, `x3`, `argus`, `dual-light` or `f10`.
    pub const fn name(self) -> &'static str {
        match self {
            Family::A2000 => "a2000",
            Family::X3 => "x3",
            Family::Argus => "argus",
            Family::DualLight => "dual-light",
            Family::F10 => "f10",
        }
    }

    /// The family named `name` (one of [`Family::name`]'s, ASCII case ignored).
    ///
    /// # Errors
    /// [`VideoError::UnknownFamily`] for any other name.
    pub fn from_name(name: &str) -> Result<Family, VideoError> {
        Family::ALL
            .into_iter()
            .find(|f| f.name().eq_ignore_ascii_case(name))
            .ok_or(VideoError::UnknownFamily)
    }

    /// The streams the family's camera offers, main first.
    pub const fn streams(self) -> &'static [Stream] {
        match self {
            Family::A2000 | Family::F10 => &[Stream::Main],
            Family::X3 | Family::Argus => &[Stream::Main, Stream::Aux1, Stream::Aux2],
            Family::DualLight => &[Stream::Main, Stream::Aux1, Stream::Infrared],
        }
    }

    /// Whether the family's camera offers `stream`.
    pub const fn has(self, stream: Stream) -> bool {
        form(self, stream).is_some()
    }

    /// Whether the family's addresses carry credentials (all but A2000 and F10).
    pub const fn uses_credentials(self) -> bool {
        !matches!(self, Family::A2000 | Family::F10)
    }
}

impl fmt::Display for Family {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Family {
    type Err = VideoError;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Family::from_name(s)
    }
}

/// A video stream of a camera ("code stream" in the document).
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Stream {
    /// The main stream (`subtype=0`; the only stream of A2000 and F10).
    Main,
    /// Auxiliary stream 1 (`subtype=1`).
    Aux1,
    /// Auxiliary stream 2 (`subtype=2`; X3 and Argus only).
    Aux2,
    /// The infrared stream (`subtype=2`; dual-light only).
    Infrared,
}

impl Stream {
    /// Every stream kind.
    pub const ALL: [Stream; 4] = [Stream::Main, Stream::Aux1, Stream::Aux2, Stream::Infrared];

    /// The stream's command-line name: `main`, `aux1`, `aux2` or `infrared`.
    pub const fn name(self) -> &'static str {
        match self {
            Stream::Main => "main",
            Stream::Aux1 => "aux1",
            Stream::Aux2 => "aux2",
            Stream::Infrared => "infrared",
        }
    }

    /// The stream named `name` (one of [`Stream::name`]'s, ASCII case ignored).
    ///
    /// # Errors
    /// [`VideoError::UnknownStream`] for any other name.
    pub fn from_name(name: &str) -> Result<Stream, VideoError> {
        Stream::ALL
            .into_iter()
            .find(|s| s.name().eq_ignore_ascii_case(name))
            .ok_or(VideoError::UnknownStream)
    }
}

impl fmt::Display for Stream {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Stream {
    type Err = VideoError;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Stream::from_name(s)
    }
}

/// The user name and password of a camera's RTSP streams.
///
/// Any text is accepted: it is percent-encoded into the address (see the
/// [module docs](self#credentials)). Each may be at most [`Credentials::MAX_LEN`] bytes.
/// [`Debug`] shows the user name but not the password.
#[derive(Clone, Copy, PartialEq, Eq, Hash)]
pub struct Credentials<'a> {
    /// The user name.
    pub user: &'a str,
    /// The password.
    pub password: &'a str,
}

impl<'a> Credentials<'a> {
    /// The document's credentials, `admin:admin` (section 1.3).
    pub const DEFAULT: Credentials<'static> = Credentials {
        user: "admin",
        password: "admin",
    };

    /// The longest user name or password, in bytes (UTF-8) before encoding: 32, as on
    /// the IP cameras whose address scheme these streams use.
    pub const MAX_LEN: usize = 32;

    /// Credentials with the given user name and password.
    pub const fn new(user: &'a str, password: &'a str) -> Self {
        Credentials { user, password }
    }

    /// Checks both lengths against [`Credentials::MAX_LEN`].
    fn check(&self) -> Result<(), VideoError> {
        for (field, text) in [
            (CredentialField::User, self.user),
            (CredentialField::Password, self.password),
        ] {
            if text.len() > Self::MAX_LEN {
                return Err(VideoError::CredentialTooLong {
                    field,
                    len: text.len(),
                });
            }
        }
        Ok(())
    }
}

impl Default for Credentials<'static> {
    fn default() -> Self {
        Credentials::DEFAULT
    }
}

impl fmt::Debug for Credentials<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Credentials")
            .field("user", &self.user)
            .field("password", &"<redacted>")
            .finish()
    }
}

#[cfg(feature = "defmt")]
impl defmt::Format for Credentials<'_> {
    fn format(&self, f: defmt::Formatter<'_>) {
        defmt::write!(
            f,
            "Credentials {{ user: {=str}, password: <redacted> }}",
            self.user
        )
    }
}

/// Which of the two credentials a [`VideoError::CredentialTooLong`] is about.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum CredentialField {
    /// The user name.
    User,
    /// The password.
    Password,
}

impl CredentialField {
    /// `"user name"` or `"password"`.
    pub const fn name(self) -> &'static str {
        match self {
            CredentialField::User => "user name",
            CredentialField::Password => "password",
        }
    }
}

impl fmt::Display for CredentialField {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// A camera: its family, IP address and stream credentials.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Camera<'a> {
    /// Which family of section 1.3 the camera is.
    pub family: Family,
    /// The camera's IP address.
    pub ip: Ipv4Addr,
    /// The stream credentials (ignored by families whose addresses have none).
    pub credentials: Credentials<'a>,
}

impl Camera<'static> {
    /// A camera of `family` at [`DEFAULT_IP`] with [`Credentials::DEFAULT`].
    pub const fn new(family: Family) -> Self {
        Camera {
            family,
            ip: DEFAULT_IP,
            credentials: Credentials::DEFAULT,
        }
    }
}

impl<'a> Camera<'a> {
    /// The same camera at another IP address.
    pub const fn with_ip(self, ip: Ipv4Addr) -> Self {
        Camera { ip, ..self }
    }

    /// The same camera with other credentials.
    pub const fn with_credentials<'b>(self, credentials: Credentials<'b>) -> Camera<'b> {
        Camera {
            family: self.family,
            ip: self.ip,
            credentials,
        }
    }

    /// The validated address of `stream`, which formats (with [`Display`](fmt::Display))
    /// as its URL.
    ///
    /// # Errors
    /// [`VideoError::NoSuchStream`] if the family has no such stream;
    /// [`VideoError::CredentialTooLong`] if the family's addresses carry credentials and
    /// one of them is longer than [`Credentials::MAX_LEN`].
    pub fn address(&self, stream: Stream) -> Result<Address<'a>, VideoError> {
        let form = form(self.family, stream).ok_or(VideoError::NoSuchStream {
            family: self.family,
            stream,
        })?;
        if matches!(form, Form::RealMonitor(_)) {
            self.credentials.check()?;
        }
        Ok(Address {
            camera: *self,
            stream,
            form,
        })
    }

    /// Writes the URL of `stream` into `out`.
    ///
    /// # Errors
    /// Those of [`Camera::address`], and [`VideoError::DoesNotFit`] if `out` fails to take
    /// the whole URL (for a fixed-capacity writer: it is too small). `out` may then hold
    /// the beginning of the URL.
    pub fn write_url<W: fmt::Write + ?Sized>(
        &self,
        stream: Stream,
        out: &mut W,
    ) -> Result<(), VideoError> {
        let address = self.address(stream)?;
        address
            .write_to(out)
            .map_err(|_| VideoError::DoesNotFit { len: address.len() })
    }

    /// The URL of `stream`, in a string of [`URL_CAPACITY`] bytes (always large enough).
    ///
    /// # Errors
    /// Those of [`Camera::address`].
    pub fn url(&self, stream: Stream) -> Result<heapless::String<URL_CAPACITY>, VideoError> {
        let mut out = heapless::String::new();
        self.write_url(stream, &mut out)?;
        Ok(out)
    }
}

/// The address of one stream of one camera, checked by [`Camera::address`]. Its
/// [`Display`](fmt::Display) output is the URL.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Address<'a> {
    camera: Camera<'a>,
    stream: Stream,
    form: Form,
}

impl<'a> Address<'a> {
    /// The camera.
    pub const fn camera(&self) -> Camera<'a> {
        self.camera
    }

    /// The stream.
    pub const fn stream(&self) -> Stream {
        self.stream
    }

    /// The length of the URL in bytes (at most [`URL_CAPACITY`]).
    pub fn len(&self) -> usize {
        let mut counter = Counter(0);
        // Counter never fails, and writing the address only fails if the writer does.
        let _ = self.write_to(&mut counter);
        counter.0
    }

    /// Always false: a URL is never empty. (For symmetry with [`Address::len`].)
    pub const fn is_empty(&self) -> bool {
        false
    }
}

impl Address<'_> {
    /// Writes the URL with `write_str` only: no `core::fmt` machinery (`fmt::write`, the
    /// integer formatting and padding behind `{}`), which on a microcontroller costs about
    /// 3 KiB of flash for what is a handful of string pieces and four small numbers.
    fn write_to<W: fmt::Write + ?Sized>(&self, out: &mut W) -> fmt::Result {
        out.write_str("rtsp://")?;
        if let Form::RealMonitor(_) = self.form {
            let credentials = self.camera.credentials;
            for piece in utf8_percent_encode(credentials.user, USERINFO) {
                out.write_str(piece)?;
            }
            out.write_str(":")?;
            for piece in utf8_percent_encode(credentials.password, USERINFO) {
                out.write_str(piece)?;
            }
            out.write_str("@")?;
        }
        for (i, octet) in self.camera.ip.octets().into_iter().enumerate() {
            if i > 0 {
                out.write_str(".")?;
            }
            write_decimal(out, octet)?;
        }
        out.write_str(":")?;
        write_decimal(out, interface::RTSP_PORT)?;
        match self.form {
            Form::Live => out.write_str("/live"),
            Form::AvStream => out.write_str("/ch1/sub/av_stream"),
            Form::RealMonitor(subtype) => {
                out.write_str("/cam/realmonitor?channel=1&subtype=")?;
                write_decimal(out, subtype)
            }
        }
    }
}

/// `n` in decimal, with `write_char` only.
fn write_decimal<W: fmt::Write + ?Sized>(out: &mut W, n: impl Into<u32>) -> fmt::Result {
    let mut n: u32 = n.into();
    let mut digits = [0u8; 10];
    let mut start = digits.len();
    // From the last digit back: ten places hold any u32.
    for (i, d) in digits.iter_mut().enumerate().rev() {
        // A digit: n % 10 < 10, so the sum is exact.
        *d = b'0'.saturating_add((n % 10) as u8);
        n /= 10;
        start = i;
        if n == 0 {
            break;
        }
    }
    // Digit by digit: `str::from_utf8` on them would link its validator (368 B on the
    // Cortex-M4) for bytes that are ASCII by construction.
    digits
        .get(start..)
        .unwrap_or(&[])
        .iter()
        .try_for_each(|&d| out.write_char(char::from(d)))
}

impl fmt::Display for Address<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        self.write_to(f)
    }
}

/// The form of a stream's address.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
enum Form {
    /// `rtsp://IP:554/live`
    Live,
    /// `rtsp://IP:554/ch1/sub/av_stream`
    AvStream,
    /// `rtsp://USER:PASS@IP:554/cam/realmonitor?channel=1&subtype=N`
    RealMonitor(u8),
}

/// The address form of `stream` on `family`, or `None` if the family lacks it.
const fn form(family: Family, stream: Stream) -> Option<Form> {
    match (family, stream) {
        (Family::A2000, Stream::Main) => Some(Form::Live),
        (Family::F10, Stream::Main) => Some(Form::AvStream),
        (Family::X3 | Family::Argus | Family::DualLight, Stream::Main) => {
            Some(Form::RealMonitor(0))
        }
        (Family::X3 | Family::Argus | Family::DualLight, Stream::Aux1) => {
            Some(Form::RealMonitor(1))
        }
        (Family::X3 | Family::Argus, Stream::Aux2) => Some(Form::RealMonitor(2)),
        (Family::DualLight, Stream::Infrared) => Some(Form::RealMonitor(2)),
        _ => None,
    }
}

/// A [`fmt::Write`] that only counts bytes.
struct Counter(usize);

impl fmt::Write for Counter {
    fn write_str(&mut self, s: &str) -> fmt::Result {
        self.0 = self.0.saturating_add(s.len());
        Ok(())
    }
}

/// Why a stream address could not be given.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum VideoError {
    /// The family's camera has no such stream (see [`Family::streams`]).
    NoSuchStream {
        /// The camera family.
        family: Family,
        /// The stream asked for.
        stream: Stream,
    },
    /// A user name or password is longer than [`Credentials::MAX_LEN`] bytes.
    CredentialTooLong {
        /// Which one.
        field: CredentialField,
        /// Its length in bytes.
        len: usize,
    },
    /// The output did not take the whole URL (a fixed-capacity writer that is too small).
    DoesNotFit {
        /// The URL's length in bytes.
        len: usize,
    },
    /// A family name that is none of [`Family::name`]'s.
    UnknownFamily,
    /// A stream name that is none of [`Stream::name`]'s.
    UnknownStream,
}

impl fmt::Display for VideoError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            VideoError::NoSuchStream { family, stream } => {
                write!(f, "{family} has no {stream} stream; it has: ")?;
                write_list(f, family.streams().iter().map(|s| s.name()))
            }
            VideoError::CredentialTooLong { field, len } => write!(
                f,
                "the camera {field} is {len} bytes long; at most {} bytes are allowed",
                Credentials::MAX_LEN
            ),
            VideoError::DoesNotFit { len } => write!(
                f,
                "the stream address is {len} bytes long and does not fit in the output; \
                 give it room for {len} bytes ({URL_CAPACITY} fit every address)"
            ),
            VideoError::UnknownFamily => {
                f.write_str("unknown camera family; valid: ")?;
                write_list(f, Family::ALL.iter().map(|s| s.name()))
            }
            VideoError::UnknownStream => {
                f.write_str("unknown stream; valid: ")?;
                write_list(f, Stream::ALL.iter().map(|s| s.name()))
            }
        }
    }
}

/// Writes `items` separated by `", "`.
fn write_list<'s>(f: &mut fmt::Formatter<'_>, items: impl Iterator<Item = &'s str>) -> fmt::Result {
    for (i, item) in items.enumerate() {
        if i > 0 {
            f.write_str(", ")?;
        }
        f.write_str(item)?;
    }
    Ok(())
}

#[cfg(feature = "std")]
impl std::error::Error for VideoError {}

#[cfg(test)]
mod tests {
    use super::*;

    fn url(camera: Camera<'_>, stream: Stream) -> Result<String, VideoError> {
        camera.url(stream).map(|s| s.as_str().to_owned())
    }

    #[test]
    fn default_addresses_of_every_stream() {
        let cases: [(Family, Stream, &str); 11] = [
            (
                Family::A2000,
                Stream::Main,
                "rtsp://192.168.42.108:554/live",
            ),
            (
                Family::X3,
                Stream::Main,
                "rtsp://admin:admin@192.168.42.108:554/cam/realmonitor?channel=1&subtype=0",
            ),
            (
                Family::X3,
                Stream::Aux1,
                "rtsp://admin:admin@192.168.42.108:554/cam/realmonitor?channel=1&subtype=1",
            ),
            (
                Family::X3,
                Stream::Aux2,
                "rtsp://admin:admin@192.168.42.108:554/cam/realmonitor?channel=1&subtype=2",
            ),
            (
                Family::Argus,
                Stream::Main,
                "rtsp://admin:admin@192.168.42.108:554/cam/realmonitor?channel=1&subtype=0",
            ),
            (
                Family::Argus,
                Stream::Aux1,
                "rtsp://admin:admin@192.168.42.108:554/cam/realmonitor?channel=1&subtype=1",
            ),
            (
                Family::Argus,
                Stream::Aux2,
                "rtsp://admin:admin@192.168.42.108:554/cam/realmonitor?channel=1&subtype=2",
            ),
            (
                Family::DualLight,
                Stream::Main,
                "rtsp://admin:admin@192.168.42.108:554/cam/realmonitor?channel=1&subtype=0",
            ),
            (
                Family::DualLight,
                Stream::Aux1,
                "rtsp://admin:admin@192.168.42.108:554/cam/realmonitor?channel=1&subtype=1",
            ),
            (
                Family::DualLight,
                Stream::Infrared,
                "rtsp://admin:admin@192.168.42.108:554/cam/realmonitor?channel=1&subtype=2",
            ),
            (
                Family::F10,
                Stream::Main,
                "rtsp://192.168.42.108:554/ch1/sub/av_stream",
            ),
        ];
        for (family, stream, expected) in cases {
            let cam = Camera::new(family);
            assert_eq!(url(cam, stream).unwrap(), expected, "{family} {stream}");
            // The other two ways give the same text.
            let mut s = String::new();
            cam.write_url(stream, &mut s).unwrap();
            assert_eq!(s, expected);
            let addr = cam.address(stream).unwrap();
            assert_eq!(addr.to_string(), expected);
            assert_eq!((addr.len(), addr.is_empty()), (expected.len(), false));
            assert_eq!((addr.stream(), addr.camera()), (stream, cam));
        }
        // Every (family, stream) pair a family has is covered above.
        let n: usize = Family::ALL.iter().map(|f| f.streams().len()).sum();
        assert_eq!(n, cases.len());
    }

    #[test]
    fn custom_ip_and_credentials() {
        let ip = Ipv4Addr::new(10, 1, 2, 254);
        let creds = Credentials::new("operator", "S3cret-pw_1.~");
        let cases: [(Family, Stream, &str); 11] = [
            (Family::A2000, Stream::Main, "rtsp://10.1.2.254:554/live"),
            (
                Family::X3,
                Stream::Main,
                "rtsp://operator:S3cret-pw_1.~@10.1.2.254:554/cam/realmonitor?channel=1&subtype=0",
            ),
            (
                Family::X3,
                Stream::Aux1,
                "rtsp://operator:S3cret-pw_1.~@10.1.2.254:554/cam/realmonitor?channel=1&subtype=1",
            ),
            (
                Family::X3,
                Stream::Aux2,
                "rtsp://operator:S3cret-pw_1.~@10.1.2.254:554/cam/realmonitor?channel=1&subtype=2",
            ),
            (
                Family::Argus,
                Stream::Main,
                "rtsp://operator:S3cret-pw_1.~@10.1.2.254:554/cam/realmonitor?channel=1&subtype=0",
            ),
            (
                Family::Argus,
                Stream::Aux1,
                "rtsp://operator:S3cret-pw_1.~@10.1.2.254:554/cam/realmonitor?channel=1&subtype=1",
            ),
            (
                Family::Argus,
                Stream::Aux2,
                "rtsp://operator:S3cret-pw_1.~@10.1.2.254:554/cam/realmonitor?channel=1&subtype=2",
            ),
            (
                Family::DualLight,
                Stream::Main,
                "rtsp://operator:S3cret-pw_1.~@10.1.2.254:554/cam/realmonitor?channel=1&subtype=0",
            ),
            (
                Family::DualLight,
                Stream::Aux1,
                "rtsp://operator:S3cret-pw_1.~@10.1.2.254:554/cam/realmonitor?channel=1&subtype=1",
            ),
            (
                Family::DualLight,
                Stream::Infrared,
                "rtsp://operator:S3cret-pw_1.~@10.1.2.254:554/cam/realmonitor?channel=1&subtype=2",
            ),
            (
                Family::F10,
                Stream::Main,
                "rtsp://10.1.2.254:554/ch1/sub/av_stream",
            ),
        ];
        for (family, stream, expected) in cases {
            let cam = Camera::new(family).with_ip(ip).with_credentials(creds);
            assert_eq!(url(cam, stream).unwrap(), expected, "{family} {stream}");
        }
        // Only the IP, or only the credentials.
        assert_eq!(
            url(
                Camera::new(Family::X3).with_ip(Ipv4Addr::new(172, 16, 0, 1)),
                Stream::Main
            )
            .unwrap(),
            "rtsp://admin:admin@172.16.0.1:554/cam/realmonitor?channel=1&subtype=0"
        );
        assert_eq!(
            url(
                Camera::new(Family::DualLight).with_credentials(Credentials::new("u", "p")),
                Stream::Infrared
            )
            .unwrap(),
            "rtsp://u:p@192.168.42.108:554/cam/realmonitor?channel=1&subtype=2"
        );
        // Families without credentials ignore them, even over-long ones.
        let long = "x".repeat(100);
        let cam = Camera::new(Family::F10).with_credentials(Credentials::new(&long, &long));
        assert_eq!(
            url(cam, Stream::Main).unwrap(),
            "rtsp://192.168.42.108:554/ch1/sub/av_stream"
        );
    }

    #[test]
    fn credentials_needing_encoding_give_the_exact_encoded_url() {
        let cam = Camera::new(Family::X3).with_credentials(Credentials::new(
            "op@site:1",
            "a/b?c#d[e]f%g h\u{e9}\u{1}!$&'()*+,;=",
        ));
        assert_eq!(
            url(cam, Stream::Aux2).unwrap(),
            "rtsp://op%40site%3A1:a%2Fb%3Fc%23d%5Be%5Df%25g%20h%C3%A9%01%21%24%26%27%28%29%2A%2B%2C%3B%3D\
             @192.168.42.108:554/cam/realmonitor?channel=1&subtype=2"
        );
        // Unreserved characters stay as they are.
        let cam = Camera::new(Family::Argus).with_credentials(Credentials::new("AZaz09-._~", ""));
        assert_eq!(
            url(cam, Stream::Main).unwrap(),
            "rtsp://AZaz09-._~:@192.168.42.108:554/cam/realmonitor?channel=1&subtype=0"
        );
    }

    #[test]
    fn longest_address_fills_the_capacity_exactly() {
        let user = "\u{7f}".repeat(Credentials::MAX_LEN); // DEL: one byte, encoded to three
        let password = "\u{e9}".repeat(Credentials::MAX_LEN / 2); // 2 bytes each
        let cam = Camera::new(Family::X3)
            .with_ip(Ipv4Addr::new(255, 255, 255, 255))
            .with_credentials(Credentials::new(&user, &password));
        let u = cam.url(Stream::Main).unwrap();
        assert_eq!(u.len(), URL_CAPACITY);
        assert_eq!(
            u.as_str(),
            format!(
                "rtsp://{}:{}@255.255.255.255:554/cam/realmonitor?channel=1&subtype=0",
                "%7F".repeat(32),
                "%C3%A9".repeat(16)
            )
        );
        assert_eq!(URL_CAPACITY, 256);
    }

    #[test]
    fn missing_streams_are_errors() {
        let missing: [(Family, &[Stream]); 5] = [
            (
                Family::A2000,
                &[Stream::Aux1, Stream::Aux2, Stream::Infrared],
            ),
            (Family::X3, &[Stream::Infrared]),
            (Family::Argus, &[Stream::Infrared]),
            (Family::DualLight, &[Stream::Aux2]),
            (Family::F10, &[Stream::Aux1, Stream::Aux2, Stream::Infrared]),
        ];
        for (family, streams) in missing {
            for &stream in streams {
                let expected = VideoError::NoSuchStream { family, stream };
                assert_eq!(Camera::new(family).url(stream), Err(expected));
                assert_eq!(Camera::new(family).address(stream), Err(expected));
                let mut s = String::new();
                assert_eq!(Camera::new(family).write_url(stream, &mut s), Err(expected));
                assert_eq!(s, "", "nothing written");
                assert!(!family.has(stream));
            }
            // has() and streams() agree with what the family lacks.
            for stream in Stream::ALL {
                assert_eq!(family.has(stream), !streams.contains(&stream));
                assert_eq!(
                    family.streams().contains(&stream),
                    !streams.contains(&stream)
                );
            }
        }
    }

    #[test]
    fn error_messages_name_the_problem_and_what_is_valid() {
        let e = |family, stream| VideoError::NoSuchStream { family, stream }.to_string();
        assert_eq!(
            e(Family::A2000, Stream::Aux1),
            "a2000 has no aux1 stream; it has: main"
        );
        assert_eq!(
            e(Family::X3, Stream::Infrared),
            "x3 has no infrared stream; it has: main, aux1, aux2"
        );
        assert_eq!(
            e(Family::Argus, Stream::Infrared),
            "argus has no infrared stream; it has: main, aux1, aux2"
        );
        assert_eq!(
            e(Family::DualLight, Stream::Aux2),
            "dual-light has no aux2 stream; it has: main, aux1, infrared"
        );
        assert_eq!(
            e(Family::F10, Stream::Infrared),
            "f10 has no infrared stream; it has: main"
        );
        assert_eq!(
            VideoError::CredentialTooLong {
                field: CredentialField::Password,
                len: 40
            }
            .to_string(),
            "the camera password is 40 bytes long; at most 32 bytes are allowed"
        );
        assert_eq!(
            VideoError::DoesNotFit { len: 43 }.to_string(),
            "the stream address is 43 bytes long and does not fit in the output; \
             give it room for 43 bytes (256 fit every address)"
        );
        assert_eq!(
            VideoError::UnknownFamily.to_string(),
            "unknown camera family; valid: a2000, x3, argus, dual-light, f10"
        );
        assert_eq!(
            VideoError::UnknownStream.to_string(),
            "unknown stream; valid: main, aux1, aux2, infrared"
        );
    }

    #[test]
    fn too_small_output_is_an_error() {
        // F10's address is 43 bytes: 42 is one too few, 43 is enough.
        let cam = Camera::new(Family::F10);
        let mut out: heapless::String<42> = heapless::String::new();
        assert_eq!(
            cam.write_url(Stream::Main, &mut out),
            Err(VideoError::DoesNotFit { len: 43 })
        );
        let mut out: heapless::String<43> = heapless::String::new();
        assert_eq!(cam.write_url(Stream::Main, &mut out), Ok(()));
        assert_eq!(out.as_str(), "rtsp://192.168.42.108:554/ch1/sub/av_stream");
        // The realmonitor form with default credentials: 73 bytes.
        let cam = Camera::new(Family::DualLight);
        let mut out: heapless::String<72> = heapless::String::new();
        assert_eq!(
            cam.write_url(Stream::Aux1, &mut out),
            Err(VideoError::DoesNotFit { len: 73 })
        );
        // The length counts the encoded credentials.
        let cam = cam.with_credentials(Credentials::new("a b c", "admin"));
        let mut out: heapless::String<76> = heapless::String::new();
        assert_eq!(
            cam.write_url(Stream::Aux1, &mut out),
            Err(VideoError::DoesNotFit { len: 77 })
        );
    }

    #[test]
    fn overlong_credentials_are_errors() {
        let long = "u".repeat(Credentials::MAX_LEN + 1);
        let ok = "u".repeat(Credentials::MAX_LEN);
        let cam = Camera::new(Family::X3);
        assert_eq!(
            cam.with_credentials(Credentials::new(&long, "p"))
                .url(Stream::Main),
            Err(VideoError::CredentialTooLong {
                field: CredentialField::User,
                len: 33
            })
        );
        assert_eq!(
            cam.with_credentials(Credentials::new("u", &long))
                .url(Stream::Aux1),
            Err(VideoError::CredentialTooLong {
                field: CredentialField::Password,
                len: 33
            })
        );
        // Bytes, not characters: 17 two-byte characters are 34 bytes.
        let wide = "\u{e9}".repeat(17);
        assert_eq!(
            cam.with_credentials(Credentials::new(&wide, "p"))
                .url(Stream::Main),
            Err(VideoError::CredentialTooLong {
                field: CredentialField::User,
                len: 34
            })
        );
        assert!(cam
            .with_credentials(Credentials::new(&ok, &ok))
            .url(Stream::Main)
            .is_ok());
        // A missing stream is reported before the credentials.
        assert_eq!(
            cam.with_credentials(Credentials::new(&long, &long))
                .url(Stream::Infrared),
            Err(VideoError::NoSuchStream {
                family: Family::X3,
                stream: Stream::Infrared
            })
        );
    }

    #[test]
    fn names_round_trip_and_unknown_names_are_errors() {
        let families: Vec<&str> = Family::ALL.iter().map(|f| f.name()).collect();
        assert_eq!(families, ["a2000", "x3", "argus", "dual-light", "f10"]);
        let streams: Vec<&str> = Stream::ALL.iter().map(|s| s.name()).collect();
        assert_eq!(streams, ["main", "aux1", "aux2", "infrared"]);
        for f in Family::ALL {
            assert_eq!(Family::from_name(f.name()), Ok(f));
            assert_eq!(f.name().parse::<Family>(), Ok(f));
            assert_eq!(f.to_string(), f.name());
        }
        for s in Stream::ALL {
            assert_eq!(Stream::from_name(s.name()), Ok(s));
            assert_eq!(s.name().parse::<Stream>(), Ok(s));
            assert_eq!(s.to_string(), s.name());
        }
        assert_eq!(Family::from_name("Dual-Light"), Ok(Family::DualLight));
        assert_eq!(Stream::from_name("IR"), Err(VideoError::UnknownStream));
        assert_eq!(Stream::from_name("MAIN"), Ok(Stream::Main));
        for bad in ["", "dual_light", "duallight", "x30", "a2000 "] {
            assert_eq!(Family::from_name(bad), Err(VideoError::UnknownFamily));
        }
        for bad in ["", "aux", "aux3", "sub"] {
            assert_eq!(Stream::from_name(bad), Err(VideoError::UnknownStream));
        }
    }

    #[test]
    fn streams_and_credential_use_per_family() {
        assert_eq!(Family::A2000.streams(), &[Stream::Main]);
        assert_eq!(Family::F10.streams(), &[Stream::Main]);
        for f in [Family::X3, Family::Argus] {
            assert_eq!(f.streams(), &[Stream::Main, Stream::Aux1, Stream::Aux2]);
        }
        assert_eq!(
            Family::DualLight.streams(),
            &[Stream::Main, Stream::Aux1, Stream::Infrared]
        );
        let with: Vec<Family> = Family::ALL
            .into_iter()
            .filter(|f| f.uses_credentials())
            .collect();
        assert_eq!(with, [Family::X3, Family::Argus, Family::DualLight]);
        assert_eq!(DEFAULT_IP, Ipv4Addr::new(192, 168, 42, 108));
        assert_eq!(Credentials::default(), Credentials::new("admin", "admin"));
    }

    #[test]
    fn debug_hides_the_password() {
        let c = Credentials::new("pilot", "hunter2");
        let shown = format!("{c:?} {:?}", Camera::new(Family::X3).with_credentials(c));
        assert!(shown.contains("pilot"));
        assert!(!shown.contains("hunter2"), "{shown}");
    }
}
