//! The OBJ file handed to tobj one line at a time: counting lines for tobj's errors, checking
//! every face's indices as it comes, and hiding what tobj would misread (see the module
//! documentation of `scene/obj`).

use std::borrow::Cow;
use std::collections::HashSet;
use std::io::{self, BufRead, Read};
use std::path::Path;

use super::libraries::Shared;
use crate::scene::mesh_file::{LoadError, Location, quoted};

/// What the reader hands to tobj for a line.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Serving {
    /// The line as it is in the file.
    Text,
    /// The line as rewritten into the scratch buffer.
    Scratch,
    /// Nothing: the end of the file, or a line tobj would ignore or misread.
    Nothing,
}

/// The OBJ file, handed to tobj one line at a time (see the module documentation for why).
pub(super) struct ObjLines<'a> {
    path: &'a Path,
    text: &'a [u8],
    shared: &'a Shared<'a>,
    /// Where the next line starts.
    next_line: usize,
    /// The number of the current line.
    pub(super) line: u64,
    /// The current line's bytes in `text` (at the end of the file, still the last line's).
    current: (usize, usize),
    /// What tobj is given for the current line.
    serving: Serving,
    scratch: Vec<u8>,
    /// How much of the current line tobj has consumed.
    consumed: usize,
    /// How many `v`, `vt` and `vn` lines came so far.
    positions: usize,
    texcoords: usize,
    normals: usize,
    /// Corners of the faces kept, and how many of them have a texture coordinate or normal.
    pub(super) corners: u64,
    pub(super) corners_with_uv: u64,
    pub(super) corners_with_normal: u64,
    pub(super) short_faces: u64,
    pub(super) polylines: u64,
    /// Each name `usemtl` uses, with the first line that uses it.
    pub(super) material_uses: Vec<(String, u64)>,
    pub(super) material_names: HashSet<String>,
}

impl<'a> ObjLines<'a> {
    pub(super) fn new(path: &'a Path, text: &'a [u8], shared: &'a Shared<'a>) -> Self {
        ObjLines {
            path,
            text,
            shared,
            next_line: 0,
            line: 0,
            current: (0, 0),
            serving: Serving::Nothing,
            scratch: Vec::new(),
            consumed: 0,
            positions: 0,
            texcoords: 0,
            normals: 0,
            corners: 0,
            corners_with_uv: 0,
            corners_with_normal: 0,
            short_faces: 0,
            polylines: 0,
            material_uses: Vec::new(),
            material_names: HashSet::new(),
        }
    }

    fn served(&self) -> &[u8] {
        match self.serving {
            Serving::Text => &self.text[self.current.0..self.current.1],
            Serving::Scratch => &self.scratch,
            Serving::Nothing => &[],
        }
    }

    /// The current line of the file, as text.
    pub(super) fn last_line_text(&self) -> Cow<'a, str> {
        String::from_utf8_lossy(&self.text[self.current.0..self.current.1])
    }

    /// Moves to the next line that tobj should see, or to the end of the file.
    fn advance(&mut self) -> io::Result<()> {
        loop {
            self.consumed = 0;
            self.serving = Serving::Nothing;
            if self.shared.failure.borrow().is_some() {
                return Err(io::Error::other("stopped"));
            }
            let text = self.text;
            let Some(rest) = text.get(self.next_line..).filter(|rest| !rest.is_empty()) else {
                return Ok(());
            };
            let length = rest.iter().position(|&b| b == b'\n').map_or(rest.len(), |n| n + 1);
            self.current = (self.next_line, self.next_line + length);
            self.next_line += length;
            self.line += 1;
            self.shared.line.set(self.line);
            match self.inspect(&rest[..length]) {
                Ok(Serving::Nothing) => continue,
                Ok(serving) => {
                    self.serving = serving;
                    return Ok(());
                }
                Err(message) => {
                    let location = Location::Line(self.line);
                    let error = LoadError::Syntax { path: self.path.into(), location, message };
                    self.shared.failure.borrow_mut().get_or_insert(error);
                    return Err(io::Error::other("stopped"));
                }
            }
        }
    }

    /// Decides what tobj gets for `raw`, checking faces and counting what is defined.
    fn inspect(&mut self, raw: &[u8]) -> Result<Serving, String> {
        let line = match std::str::from_utf8(raw) {
            Ok(line) => Cow::Borrowed(line),
            Err(_) => String::from_utf8_lossy(raw),
        };
        let mut words = line.split_whitespace();
        let serve = match words.next() {
            None => return Ok(Serving::Nothing),
            Some(word) if word.starts_with('#') => return Ok(Serving::Nothing),
            Some("v") => {
                self.positions += 1;
                // Seven words need six separators; counting bytes first is cheaper than splitting.
                let separators = raw.iter().filter(|b| b.is_ascii_whitespace()).count();
                if (separators >= 6 || !raw.is_ascii()) && words.clone().count() == 6 {
                    // x y z r g b: tobj wants colours on every vertex or none; we need none.
                    let xyz: Vec<&str> = words.take(3).collect();
                    self.scratch = format!("v {}\n", xyz.join(" ")).into_bytes();
                    return Ok(Serving::Scratch);
                }
                Serving::Text
            }
            Some("vt") => {
                self.texcoords += 1;
                Serving::Text
            }
            Some("vn") => {
                self.normals += 1;
                Serving::Text
            }
            Some("f") => match self.check_face(words)? {
                0 => return Err("expected face corners after `f`".into()),
                1 | 2 => {
                    self.short_faces += 1;
                    return Ok(Serving::Nothing);
                }
                _ => Serving::Text,
            },
            Some("l") => {
                self.polylines += 1;
                return Ok(Serving::Nothing);
            }
            Some("usemtl") => {
                // The name as tobj reads it: everything after the first space.
                let name = line.split_once(' ').map_or("", |(_, rest)| rest).trim();
                if !name.is_empty() && !self.material_names.contains(name) {
                    self.material_names.insert(name.to_string());
                    self.material_uses.push((name.to_string(), self.line));
                }
                Serving::Text
            }
            Some(_) => Serving::Text,
        };
        if let Cow::Owned(line) = line {
            self.scratch = line.into_bytes();
            return Ok(Serving::Scratch);
        }
        Ok(serve)
    }

    /// Checks a face's corners against what is defined so far; returns how many there are.
    fn check_face<'w>(&mut self, corners: impl Iterator<Item = &'w str>) -> Result<u64, String> {
        let (mut count, mut with_uv, mut with_normal) = (0, 0, 0);
        for corner in corners {
            count += 1;
            let mut parts = corner.split('/');
            let vertex = parts.next().unwrap_or("");
            if vertex.is_empty() {
                return Err(format!("face corner {} has no vertex index", quoted(corner)));
            }
            check_index(vertex, self.positions, ("vertex", "vertices"), corner)?;
            if let Some(uv) = parts.next().filter(|t| !t.is_empty()) {
                check_index(
                    uv,
                    self.texcoords,
                    ("texture coordinate", "texture coordinates"),
                    corner,
                )?;
                with_uv += 1;
            }
            if let Some(normal) = parts.next().filter(|n| !n.is_empty()) {
                check_index(normal, self.normals, ("normal", "normals"), corner)?;
                with_normal += 1;
            }
            if parts.any(|p| !p.is_empty()) {
                return Err(format!(
                    "expected a face corner like 1, 1/2, 1//3 or 1/2/3, found {}",
                    quoted(corner)
                ));
            }
        }
        if count >= 3 {
            self.corners += count;
            self.corners_with_uv += with_uv;
            self.corners_with_normal += with_normal;
        }
        Ok(count)
    }
}

/// Checks a face index: from 1 up to `defined`, or from -1 down to `-defined`.
fn check_index(
    text: &str,
    defined: usize,
    (what, plural): (&str, &str),
    corner: &str,
) -> Result<(), String> {
    let Ok(index) = text.parse::<isize>() else {
        return Err(format!(
            "expected a {what} index in face corner {}, found {}",
            quoted(corner),
            quoted(text)
        ));
    };
    if index == 0 {
        Err(format!("{what} index 0 in face corner {}: OBJ indices start at 1", quoted(corner)))
    } else if index > 0 && index.unsigned_abs() > defined {
        Err(format!(
            "{what} index {index} is out of range: {defined} {plural} are defined before this line"
        ))
    } else if index < 0 && index.unsigned_abs() > defined {
        Err(format!(
            "relative {what} index {index} reaches before the first one: {defined} {plural} are \
             defined before this line"
        ))
    } else {
        Ok(())
    }
}

impl Read for ObjLines<'_> {
    fn read(&mut self, buffer: &mut [u8]) -> io::Result<usize> {
        let available = self.fill_buf()?;
        let n = available.len().min(buffer.len());
        buffer[..n].copy_from_slice(&available[..n]);
        self.consume(n);
        Ok(n)
    }
}

impl BufRead for ObjLines<'_> {
    fn fill_buf(&mut self) -> io::Result<&[u8]> {
        if self.consumed >= self.served().len() {
            self.advance()?;
        }
        let served = self.served();
        Ok(&served[self.consumed.min(served.len())..])
    }

    fn consume(&mut self, amount: usize) {
        self.consumed += amount;
    }
}
