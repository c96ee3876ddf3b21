//! Paths and directories over the caller's files: a request's path, the file it names, and
//! the entries of a directory as `ListDirectory` lists them.

use super::{File, MAX_DATA_LEN};

/// The path in a request: `data[..size]` up to the first NUL.
pub(super) fn path(data: &[u8; MAX_DATA_LEN], size: u8) -> &[u8] {
    let raw = data.get(..usize::from(size)).unwrap_or(&[]);
    raw.split(|&b| b == 0).next().unwrap_or(&[])
}

pub(super) fn trim_slashes(mut path: &[u8]) -> &[u8] {
    while let [b'/', rest @ ..] = path {
        path = rest;
    }
    while let [rest @ .., b'/'] = path {
        path = rest;
    }
    path
}

/// The index of the file at `path`.
pub(super) fn find_file(files: &[File<'_>], path: &[u8]) -> Option<usize> {
    let path = trim_slashes(path);
    if path.is_empty() {
        return None;
    }
    files
        .iter()
        .position(|f| trim_slashes(f.path.as_bytes()) == path)
}

/// What of `path` lies under the directory `dir` (both trimmed; `dir` empty for the root).
pub(super) fn under<'p>(dir: &[u8], path: &'p [u8]) -> Option<&'p [u8]> {
    if dir.is_empty() {
        return Some(path);
    }
    path.strip_prefix(dir)?.strip_prefix(b"/")
}

/// The sub-directory of `dir` that `file` lies in, if it lies deeper than `dir`.
pub(super) fn subdirectory<'p>(dir: &[u8], file: &File<'p>) -> Option<&'p [u8]> {
    let rest = under(dir, trim_slashes(file.path.as_bytes()))?;
    let slash = rest.iter().position(|&b| b == b'/')?;
    rest.get(..slash)
}

/// A directory entry.
#[derive(Clone, Copy, Debug)]
pub(super) enum Entry<'f> {
    File { name: &'f [u8], size: usize },
    Directory { name: &'f [u8] },
}

/// The entries directly under a directory, in file-table order; a sub-directory where
/// the first file under it is.
pub(super) struct Entries<'s, 'f, 'd> {
    pub(super) files: &'s [File<'f>],
    pub(super) dir: &'d [u8],
    pub(super) next: usize,
}

impl<'s, 'f, 'd> Entries<'s, 'f, 'd> {
    pub(super) fn new(files: &'s [File<'f>], dir: &'d [u8]) -> Self {
        Entries {
            files,
            dir,
            next: 0,
        }
    }
}

impl<'f> Iterator for Entries<'_, 'f, '_> {
    type Item = Entry<'f>;

    fn next(&mut self) -> Option<Entry<'f>> {
        loop {
            let index = self.next;
            let file = self.files.get(index)?;
            self.next = index.wrapping_add(1);
            if let Some(name) = subdirectory(self.dir, file) {
                let earlier = self.files.get(..index).unwrap_or(&[]);
                let seen = earlier
                    .iter()
                    .any(|f| subdirectory(self.dir, f) == Some(name));
                if !name.is_empty() && !seen {
                    return Some(Entry::Directory { name });
                }
            } else if let Some(name) = under(self.dir, trim_slashes(file.path.as_bytes())) {
                if !name.is_empty() {
                    return Some(Entry::File {
                        name,
                        size: file.len(),
                    });
                }
            }
        }
    }
}

/// Appends whole pieces to a buffer.
pub(super) struct Writer<'b> {
    pub(super) buf: &'b mut [u8],
    pub(super) len: usize,
}

impl Writer<'_> {
    /// Appends all of `pieces`, or nothing if they do not fit.
    pub(super) fn put_all(&mut self, pieces: &[&[u8]]) -> bool {
        let total: usize = pieces.iter().map(|p| p.len()).sum();
        let Some(dst) = self
            .len
            .checked_add(total)
            .and_then(|end| self.buf.get_mut(self.len..end))
        else {
            return false;
        };
        for (to, from) in dst.iter_mut().zip(pieces.iter().flat_map(|p| p.iter())) {
            *to = *from;
        }
        self.len = self.len.saturating_add(total);
        true
    }
}

/// `value` in decimal, written at the end of `buf`.
pub(super) fn decimal(mut value: usize, buf: &mut [u8; 20]) -> &[u8] {
    let mut len = 0usize;
    for digit in buf.iter_mut().rev() {
        // `'0'` is 0x30: a digit below 10 goes in its low bits.
        *digit = b'0' | (value % 10) as u8;
        value /= 10;
        // At most 20 digits.
        len = len.saturating_add(1);
        if value == 0 {
            break;
        }
    }
    buf.get(buf.len().saturating_sub(len)..).unwrap_or(&[])
}
