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

    /// A reader that fails with `Interrupted` on every third call, as a read cut short by a
    /// signal does; it is retried.
    struct Interrupting<R> {
        inner: R,
        calls: u32,
    }

    impl<R: Read> Read for Interrupting<R> {
        fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
            self.calls += 1;
            if self.calls.is_multiple_of(3) {
                return Err(std::io::ErrorKind::Interrupted.into());
            }
            self.inner.read(buf)
        }
    }

    /// The lines `for_each_line` gives equal the input split at each newline (a last line
    /// without one included, nothing after the last newline not), a line longer than
    /// `MAX_LINE` as `None`: for lines of every length around `MAX_LINE`, read in blocks of
    /// every size around it and much smaller, whichever reads are interrupted.
    #[test]
    fn lines_are_the_input_split_at_newlines() {
        let lengths = [
            0,
            1,
            25,
            MAX_LINE - 1,
            MAX_LINE,
            MAX_LINE + 1,
            2 * MAX_LINE + 3,
        ];
        let mut rng = fastrand::Rng::with_seed(7);
        for capacity in [1, 7, 64, MAX_LINE - 1, MAX_LINE, MAX_LINE + 1, READ_BLOCK] {
            for _ in 0..12 {
                let mut input = Vec::new();
                for _ in 0..rng.usize(1..8) {
                    let len = lengths[rng.usize(..lengths.len())];
                    input.extend((0..len).map(|_| rng.u8(b' '..=b'~')));
                    input.push(b'\n');
                }
                if rng.bool() {
                    input.pop();
                }
                let mut expected: Vec<Option<&[u8]>> = input
                    .split(|&b| b == b'\n')
                    .map(|l| (l.len() <= MAX_LINE).then_some(l))
                    .collect();
                // What follows the last newline is a line unless it is empty (an empty
                // input has no line at all).
                if input.last().is_none_or(|&b| b == b'\n') {
                    expected.pop();
                }
                let reader = std::io::BufReader::with_capacity(
                    capacity,
                    Interrupting {
                        inner: &input[..],
                        calls: 0,
                    },
                );
                let mut seen: Vec<Option<Vec<u8>>> = Vec::new();
                let mut blocks = 0;
                for_each_line(
                    reader,
                    &mut (&mut seen, &mut blocks),
                    |(seen, _), l| {
                        seen.push(l.map(<[u8]>::to_vec));
                        Ok(())
                    },
                    |(_, blocks)| {
                        **blocks += 1;
                        Ok(())
                    },
                )
                .unwrap();
                let seen: Vec<Option<&[u8]>> = seen.iter().map(Option::as_deref).collect();
                assert_eq!(seen, expected, "capacity {capacity}");
                // A block each fill of the buffer: the input's length over the capacity,
                // rounded up.
                assert_eq!(
                    blocks,
                    input.len().div_ceil(capacity),
                    "capacity {capacity}"
                );
            }
        }
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

    /// A short read is noted, a full one not.
    #[test]
    fn short_reads_are_noted() {
        let short = std::rc::Rc::new(std::cell::Cell::new(false));
        let mut reader = NoteShortReads {
            inner: &[1u8; 12][..],
            short: short.clone(),
        };
        let mut buf = [0u8; 8];
        assert_eq!(reader.read(&mut buf).unwrap(), 8);
        assert!(!short.get());
        assert_eq!(reader.read(&mut buf).unwrap(), 4);
        assert!(short.get());
        assert_eq!(reader.read(&mut buf[..0]).unwrap(), 0);
        assert!(!short.get(), "an empty buffer read whole");
    }

    /// The messages a sink got, and how many it had each time it was told the input
    /// paused.
    #[derive(Default)]
    struct Pauses {
        messages: u32,
        paused_at: Vec<u32>,
    }

    impl Sink for Pauses {
        fn record(&mut self, record: super::super::Record<'_>) -> Result<(), Failure> {
            use super::super::Record;
            if matches!(record, Record::Postback(..) | Record::Command(..)) {
                self.messages += 1;
            }
            Ok(())
        }

        fn input_paused(&mut self) -> Result<(), Failure> {
            self.paused_at.push(self.messages);
            Ok(())
        }
    }

    /// `input` as a file would be read (never about to block: the poll looks at the file
    /// returned, which must outlive the input), each third read interrupted.
    fn file_like(input: Vec<u8>) -> (Input, std::fs::File) {
        #[cfg(unix)]
        use std::os::fd::AsRawFd;
        let file = std::fs::File::open(concat!(env!("CARGO_MANIFEST_DIR"), "/Cargo.toml")).unwrap();
        let poll = Poll {
            #[cfg(unix)]
            fd: file.as_raw_fd(),
        };
        let input = Input {
            reader: Box::new(Interrupting {
                inner: std::io::Cursor::new(input),
                calls: 0,
            }),
            poll,
        };
        (input, file)
    }

    /// From an input that never blocks, the sink hears of a pause exactly when a read
    /// returned less than a whole block: once for a block and a bit, after the bit, in
    /// both modes; and interrupted reads are retried.
    #[test]
    fn a_pause_is_a_short_read_when_nothing_blocks() {
        // Serial postbacks (27 bytes each) and a log of command lines (26 bytes each), each
        // past one whole block by ten of them.
        let postback = idu_gimbal::wire::postback::Postback::default().to_stream_bytes();
        let line = b"00000F01#0F07000000000000\n";
        for (stream, unit) in [(true, &postback[..]), (false, &line[..])] {
            let input: Vec<u8> = unit
                .iter()
                .copied()
                .cycle()
                .take(READ_BLOCK + unit.len() * 10)
                .collect();
            let mut sink = Pauses::default();
            let (input, _file) = file_like(input);
            let stats = decode_into(input, stream, &mut sink).unwrap();
            assert_eq!(sink.paused_at, [sink.messages], "stream {stream}");
            assert_eq!(u64::from(sink.messages), stats.messages, "stream {stream}");
            assert_eq!(
                stats.messages,
                ((READ_BLOCK + unit.len() * 10) / unit.len()) as u64,
                "stream {stream}"
            );
        }
    }

    /// A read that fails (other than interrupted) ends decoding with the error, in both
    /// modes.
    #[test]
    fn a_failed_read_is_an_error() {
        struct Failing;
        impl Read for Failing {
            fn read(&mut self, _: &mut [u8]) -> std::io::Result<usize> {
                Err(std::io::Error::other("the device went away"))
            }
        }
        for stream in [true, false] {
            let (mut input, _file) = file_like(Vec::new());
            input.reader = Box::new(Failing);
            let Err(Failure::Runtime(text)) = decode_into(input, stream, &mut Pauses::default())
            else {
                panic!("a failed read not a runtime failure (stream {stream})");
            };
            assert_eq!(text, "cannot read input: the device went away");
        }
    }
}
