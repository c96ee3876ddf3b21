//! Reading the input: a file or stdin, a line at a time in constant memory, with the
//! pauses a live capture has; [`decode_into`] drives a decoder over it.

use std::io::{BufRead, Read};

use super::{LogDecoder, Sink, Stats, StreamDecoder, MAX_LINE};
use crate::error::Failure;

/// Input is read in blocks of this size.
const READ_BLOCK: usize = 1 << 16;

/// Calls `f` with each line of `input` (without the newline), in constant memory: lines
/// that fit in one read are passed in place; a line longer than [`MAX_LINE`] is passed as
/// `None`. `block_done` is called after the lines of each block read are passed, before
/// the next read. Both get `state`, so that both can change it.
pub fn for_each_line<R: BufRead, S>(
    mut input: R,
    state: &mut S,
    mut f: impl FnMut(&mut S, Option<&[u8]>) -> Result<(), Failure>,
    mut block_done: impl FnMut(&mut S) -> Result<(), Failure>,
) -> Result<(), Failure> {
    let mut carry: Vec<u8> = Vec::with_capacity(MAX_LINE);
    let mut overlong = false;
    loop {
        let block = match input.fill_buf() {
            Ok(b) => b,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
            Err(e) => return Err(Failure::io("cannot read input", e)),
        };
        if block.is_empty() {
            if overlong {
                f(state, None)?;
            } else if !carry.is_empty() {
                f(state, Some(&carry))?;
            }
            return Ok(());
        }
        let mut consumed = 0;
        let mut rest = block;
        while let Some(nl) = memchr::memchr(b'\n', rest) {
            let line = &rest[..nl];
            if overlong {
                f(state, None)?;
            } else if carry.is_empty() {
                if line.len() > MAX_LINE {
                    f(state, None)?;
                } else {
                    f(state, Some(line))?;
                }
            } else if carry.len() + line.len() > MAX_LINE {
                f(state, None)?;
            } else {
                carry.extend_from_slice(line);
                f(state, Some(&carry))?;
            }
            carry.clear();
            overlong = false;
            consumed += nl + 1;
            rest = &rest[nl + 1..];
        }
        // A partial line at the end of the block.
        if !overlong {
            if carry.len() + rest.len() > MAX_LINE {
                overlong = true;
                carry.clear();
            } else {
                carry.extend_from_slice(rest);
            }
        }
        consumed += rest.len();
        input.consume(consumed);
        block_done(state)?;
    }
}

/// A reader that notes whether its last read returned less than was asked for: on a pipe
/// or a terminal, the writer has nothing more for now (the next read may block), so what
/// was decoded so far should be handed over.
struct NoteShortReads<R> {
    inner: R,
    short: std::rc::Rc<std::cell::Cell<bool>>,
}

impl<R: Read> Read for NoteShortReads<R> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let n = self.inner.read(buf)?;
        self.short.set(n < buf.len());
        Ok(n)
    }
}

/// An input that can be asked whether a read would block now.
#[derive(Clone, Copy)]
struct Poll {
    #[cfg(unix)]
    fd: std::os::fd::RawFd,
}

impl Poll {
    /// Whether a read would block now: true only for a pipe, terminal or socket with
    /// nothing waiting (a regular file is always ready).
    fn would_block(self) -> bool {
        #[cfg(unix)]
        {
            let mut p = libc::pollfd {
                fd: self.fd,
                events: libc::POLLIN,
                revents: 0,
            };
            // SAFETY: one valid pollfd, timeout 0: poll only reads and writes `p`.
            let ready = unsafe { libc::poll(&mut p, 1, 0) };
            ready == 0
        }
        #[cfg(not(unix))]
        {
            false
        }
    }
}

/// A log or capture to decode: a file, or stdin.
pub struct Input {
    reader: Box<dyn Read>,
    poll: Poll,
}

/// Opens `file`, or stdin when it is absent or `-`.
pub fn open(file: Option<&str>) -> Result<Input, Failure> {
    #[cfg(unix)]
    use std::os::fd::AsRawFd;
    match file {
        None | Some("-") => {
            let stdin = std::io::stdin();
            let poll = Poll {
                #[cfg(unix)]
                fd: stdin.as_raw_fd(),
            };
            Ok(Input {
                reader: Box::new(stdin.lock()),
                poll,
            })
        }
        Some(path) => {
            let f = std::fs::File::open(path)
                .map_err(|e| Failure::io(format!("cannot open {path}"), e))?;
            let poll = Poll {
                #[cfg(unix)]
                fd: f.as_raw_fd(),
            };
            Ok(Input {
                reader: Box::new(f),
                poll,
            })
        }
    }
}

/// Decodes all of `input`, a CAN log or with `stream` a serial/TCP capture, into `sink`,
/// and returns the counters. The sink is told whenever the input pauses: a read returned
/// less than a full block, or a full one but the next would block.
pub fn decode_into(input: Input, stream: bool, sink: &mut impl Sink) -> Result<Stats, Failure> {
    let Input { reader, poll } = input;
    if stream {
        let mut reader = reader;
        let mut dec = StreamDecoder::default();
        let mut block = vec![0u8; READ_BLOCK];
        loop {
            let n = match reader.read(&mut block) {
                Ok(0) => break,
                Ok(n) => n,
                Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
                Err(e) => return Err(Failure::io("cannot read input", e)),
            };
            dec.bytes(&block[..n], sink)?;
            if n < block.len() || poll.would_block() {
                sink.input_paused()?;
            }
        }
        dec.finish(sink)?;
        Ok(dec.stats())
    } else {
        let short = std::rc::Rc::new(std::cell::Cell::new(false));
        let reader = NoteShortReads {
            inner: reader,
            short: short.clone(),
        };
        let reader = std::io::BufReader::with_capacity(READ_BLOCK, reader);
        let mut dec = LogDecoder::new();
        for_each_line(
            reader,
            &mut (&mut dec, &mut *sink),
            |(dec, sink), line| dec.line(line, *sink),
            |(_, sink)| {
                if short.get() || poll.would_block() {
                    sink.input_paused()
                } else {
                    Ok(())
                }
            },
        )?;
        dec.finish(sink)?;
        Ok(dec.stats())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `would_block` on a pipe: true while empty, false once a byte waits, true again once
    /// it is read; a regular file is always ready.
    #[cfg(unix)]
    #[test]
    fn would_block_on_pipes_not_files() {
        use std::io::Write;
        use std::os::fd::{AsRawFd, FromRawFd};
        let mut fds = [0; 2];
        // SAFETY: a valid array of two descriptors for pipe(2) to fill.
        assert_eq!(unsafe { libc::pipe(fds.as_mut_ptr()) }, 0);
        // SAFETY: both descriptors are new and owned here.
        let (mut r, mut w) = unsafe {
            (
                std::fs::File::from_raw_fd(fds[0]),
                std::fs::File::from_raw_fd(fds[1]),
            )
        };
        let poll = Poll { fd: r.as_raw_fd() };
        assert!(poll.would_block());
        w.write_all(b"x").unwrap();
        assert!(!poll.would_block());
        let mut b = [0u8; 1];
        r.read_exact(&mut b).unwrap();
        assert!(poll.would_block());
        let file = std::fs::File::open(concat!(env!("CARGO_MANIFEST_DIR"), "/Cargo.toml")).unwrap();
        assert!(!Poll {
            fd: file.as_raw_fd()
        }
        .would_block());
    }

    #[test]
    fn long_lines_do_not_grow_memory() {
        let mut input = Vec::new();
        input.extend_from_slice(b"00000F01#0F07000000000000\n");
        input.extend(std::iter::repeat_n(b'x', MAX_LINE * 3));
        input.extend_from_slice(b"\n00000F01#0F07000000000000");
        let reader = std::io::BufReader::with_capacity(64, &input[..]);
        let mut seen = Vec::new();
        for_each_line(
            reader,
            &mut seen,
            |seen, l| {
                seen.push(l.map(|l| l.to_vec()));
                Ok(())
            },
            |_| Ok(()),
        )
        .unwrap();
        assert_eq!(seen.len(), 3);
        assert_eq!(seen[0].as_deref(), Some(&b"00000F01#0F07000000000000"[..]));
        assert_eq!(seen[1], None);
        assert_eq!(seen[2].as_deref(), Some(&b"00000F01#0F07000000000000"[..]));
    }
}
