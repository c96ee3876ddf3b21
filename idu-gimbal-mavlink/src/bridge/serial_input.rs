//! Reading the autopilot's serial line into the bridge.

use core::ops::Range;

use idu_gimbal::Instant;

use super::Bridge;
use idu_gimbal::link::{Link, Medium};

/// What a firmware read from the autopilot's serial line (a UART) for the bridge: the bytes
/// the bridge has not yet taken are held here and offered again, first, at the next
/// [`SerialInput::receive`]. The bridge leaves bytes untaken when a frame waits for room in
/// its outbox ([`Bridge::receive`]): what it holds must be sent first.
///
/// `N` is the read buffer's size: any, a UART's FIFO or DMA half-buffer (64 is plenty at
/// 921,600 baud and a millisecond loop).
///
/// ```
/// use idu_gimbal::link::{Config, Link};
/// use idu_gimbal::Instant;
/// use idu_gimbal_mavlink::{Bridge, BridgeConfig, SerialInput};
///
/// let mut link: Link = Link::new(Config::default());
/// let mut bridge = Bridge::new(BridgeConfig::default().check().unwrap());
/// let mut input: SerialInput<64> = SerialInput::new();
/// // A UART with nothing waiting: `read` answers 0 bytes.
/// let nothing = |_: &mut [u8]| Ok::<usize, ()>(0);
/// input.receive(&mut bridge, &mut link, Instant::from_millis(0), nothing).unwrap();
/// assert_eq!(input.held(), 0);
/// ```
#[derive(Clone, Debug)]
pub struct SerialInput<const N: usize> {
    buf: [u8; N],
    /// What of `buf` the bridge has not taken.
    held: Range<usize>,
    /// Reads that said they gave more bytes than the buffer holds.
    overlong: u32,
}

impl<const N: usize> SerialInput<N> {
    /// An empty input.
    pub const fn new() -> Self {
        SerialInput {
            buf: [0; N],
            held: 0..0,
            overlong: 0,
        }
    }

    /// Offers the bridge what is held, then what `read` gives (into the buffer; `Ok(0)`:
    /// nothing waiting), until `read` has nothing more or a frame waits for room in the
    /// outbox: then send what [`Bridge::transmit_bytes`] holds and call again. A read error
    /// ends the call and is returned; nothing held is lost. A read that says it gave more
    /// bytes than the buffer holds is taken as the whole buffer and counted
    /// ([`SerialInput::overlong_reads`]).
    pub fn receive<const Q: usize, const T: usize, M: Medium, E>(
        &mut self,
        bridge: &mut Bridge,
        link: &mut Link<Q, T, M>,
        now: Instant,
        mut read: impl FnMut(&mut [u8]) -> Result<usize, E>,
    ) -> Result<(), E> {
        loop {
            if self.held.is_empty() {
                let n = read(&mut self.buf)?;
                if n == 0 {
                    return Ok(());
                }
                // A reader that claims more than the buffer is held to the buffer, and
                // counted.
                if n > N {
                    self.overlong = self.overlong.wrapping_add(1);
                }
                self.held = 0..n.min(N);
            }
            let bytes = self.buf.get(self.held.clone()).unwrap_or(&[]);
            let taken = bridge.receive(link, bytes, now);
            self.held.start = self.held.start.saturating_add(taken);
            if !self.held.is_empty() {
                return Ok(());
            }
        }
    }

    /// How many bytes are held, not yet taken by the bridge.
    pub fn held(&self) -> usize {
        self.held.len()
    }

    /// How many reads said they gave more bytes than the buffer holds, which breaks
    /// `read`'s contract (wraps at `u32::MAX`): each was taken as the whole buffer.
    pub fn overlong_reads(&self) -> u32 {
        self.overlong
    }
}

impl<const N: usize> Default for SerialInput<N> {
    fn default() -> Self {
        Self::new()
    }
}
