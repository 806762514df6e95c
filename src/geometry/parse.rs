//! Text inputs for geometry: heightfield CSV and a minimal Wavefront OBJ.
//!
//! The height field is read by the one table reader (`crate::csv`). The
//! OBJ reader is hand-written rather than a crate: the format is a tiny
//! subset here, and every error must name the file and line, which the OBJ
//! crates do not report. Both report [`Error::Data`].

use std::path::Path;

use glam::Vec3;

use crate::{Error, Result};

/// An error at `line` (1-based) of `path`.
fn at(path: &Path, line: usize, what: impl Into<String>) -> Error {
    Error::data(path, Some(line), "target.file", what)
}

fn read(path: &Path) -> Result<String> {
    std::fs::read_to_string(path).map_err(|e| Error::io(path, "read", e))
}

/// The part of a line before any `#` comment.
fn strip_comment(line: &str) -> &str {
    line.split('#').next().unwrap_or("")
}

/// Depths (m, negative above the water line), one grid row per line, first
/// data line y = 0; see
/// [`super::GeometryBuilder::heightfield_from_csv`].
pub(super) fn read_heightfield_csv(path: &Path) -> Result<(Vec<f32>, usize, usize)> {
    let csv = crate::csv::read(path, "bottom.heightfield")?;
    if let Some((line, _)) = &csv.header {
        return Err(csv.error(
            Some(*line),
            "a heightfield has no header: rows of depths only",
        ));
    }
    let mut depths = Vec::with_capacity(csv.rows.len() * csv.width());
    for row in &csv.rows {
        // Negative depths are land above the water line (`[land]`).
        depths.extend(csv.numbers(row)?.into_iter().map(|d| d as f32));
    }
    let (nx, rows) = (csv.width(), csv.rows.len());
    if nx < 2 || rows < 2 {
        return Err(csv.error(
            None,
            format!("a heightfield needs at least 2 rows of 2 depths, found {rows} rows of {nx}"),
        ));
    }
    Ok((depths, nx, rows))
}

/// Triangles (untransformed) of a minimal Wavefront OBJ file.
///
/// Reads `v x y z` (further values such as w or colours are ignored) and
/// `f` lines with vertex references `i`, `i/j`, `i//k` or `i/j/k` (only `i`
/// is used); indices are 1-based, negative ones count back from the last
/// vertex defined so far. Faces with more than three vertices are taken to be
/// convex and fan-triangulated. All other lines (`vt`, `vn`, `o`, `g`, `s`,
/// `usemtl`, `mtllib`, `l`, ...) and `#` comments are ignored; line
/// continuations (`\`) are not supported.
pub(super) fn read_obj(path: &Path) -> Result<Vec<[Vec3; 3]>> {
    let text = read(path)?;
    let mut vertices: Vec<Vec3> = Vec::new();
    let mut tris = Vec::new();
    let mut face: Vec<Vec3> = Vec::new();
    for (i, raw) in text.lines().enumerate() {
        let line_no = i + 1;
        let mut tokens = strip_comment(raw).split_whitespace();
        match tokens.next() {
            Some("v") => {
                let mut c = [0f32; 3];
                for value in &mut c {
                    let tok = tokens
                        .next()
                        .ok_or_else(|| at(path, line_no, "vertex needs 3 coordinates"))?;
                    *value = tok
                        .parse()
                        .map_err(|_| at(path, line_no, format!("bad vertex coordinate '{tok}'")))?;
                    if !value.is_finite() {
                        return Err(at(
                            path,
                            line_no,
                            format!("vertex coordinate '{tok}' is not finite"),
                        ));
                    }
                }
                vertices.push(Vec3::from_array(c));
            }
            Some("f") => {
                face.clear();
                for tok in tokens {
                    face.push(vertices[resolve(path, line_no, tok, vertices.len())?]);
                }
                if face.len() < 3 {
                    return Err(at(
                        path,
                        line_no,
                        format!("face with {} vertices (needs at least 3)", face.len()),
                    ));
                }
                for k in 1..face.len() - 1 {
                    tris.push([face[0], face[k], face[k + 1]]);
                }
            }
            _ => {}
        }
    }
    Ok(tris)
}

/// Index into the vertex list for the face reference `tok`, given `count`
/// vertices defined so far.
fn resolve(path: &Path, line_no: usize, tok: &str, count: usize) -> Result<usize> {
    let index = tok.split('/').next().unwrap_or("");
    let i: i64 = index
        .parse()
        .map_err(|_| at(path, line_no, format!("bad face vertex '{tok}'")))?;
    let resolved = match i {
        0 => None,
        i if i > 0 => usize::try_from(i - 1).ok(),
        // -1 is the last vertex defined so far.
        i => usize::try_from(i.unsigned_abs())
            .ok()
            .and_then(|back| count.checked_sub(back)),
    };
    match resolved {
        Some(r) if r < count => Ok(r),
        _ => Err(at(
            path,
            line_no,
            format!("face vertex index {i} out of range ({count} vertices defined so far)"),
        )),
    }
}
