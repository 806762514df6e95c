//! Reading ENVI cubes lazily: the header parsed and checked field by field,
//! values fetched with positioned reads.
//!
//! Reads what other software writes, not only littoral's own cubes: BSQ,
//! BIL or BIP; 16-bit integers (signed or not), 32- or 64-bit floats
//! (data types 2, 12, 4, 5), either byte order; the data file beside the
//! header under any of the usual names (`NAME.bsq`, `.bil`, `.bip`,
//! `.img`, `.dat`, `.raw`, or `NAME` itself). Wavelengths come from the
//! header's `wavelength`, else from the first number in each of its `band
//! names` (what `gdal_translate -of ENVI` keeps), else from the caller
//! ([`EnviCube::open_with`]). Values are returned as f32.
//!
//! Not for: writing (see the parent module) or holding a cube in memory.

use std::fs::File;
use std::io::Read;
use std::path::{Path, PathBuf};

use super::Interleave;
use crate::error::{Error, Result};

/// Headers larger than this are refused: 65 535 bands of wavelengths and
/// widths take about 2 MB, so anything larger is not an ENVI header (most
/// likely the data file passed by mistake).
const MAX_HEADER_BYTES: u64 = 16 << 20;

/// How each value is stored (ENVI `data type`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DataType {
    /// 2: 16-bit signed integer.
    I16,
    /// 12: 16-bit unsigned integer.
    U16,
    /// 4: 32-bit float.
    F32,
    /// 5: 64-bit float.
    F64,
}

impl DataType {
    fn bytes(self) -> usize {
        match self {
            DataType::I16 | DataType::U16 => 2,
            DataType::F32 => 4,
            DataType::F64 => 8,
        }
    }

    /// The value stored in `b` (`bytes()` long).
    fn decode(self, b: &[u8], big_endian: bool) -> f32 {
        macro_rules! num {
            ($t:ty, $n:literal) => {{
                let a: [u8; $n] = b.try_into().expect("value width");
                if big_endian {
                    <$t>::from_be_bytes(a)
                } else {
                    <$t>::from_le_bytes(a)
                }
            }};
        }
        match self {
            DataType::I16 => num!(i16, 2) as f32,
            DataType::U16 => num!(u16, 2) as f32,
            DataType::F32 => num!(f32, 4),
            DataType::F64 => num!(f64, 8) as f32,
        }
    }
}

/// An ENVI cube opened for random access.
#[derive(Debug)]
pub struct EnviCube {
    header_path: PathBuf,
    data_path: PathBuf,
    file: File,
    samples: usize,
    lines: usize,
    bands: usize,
    header_offset: u64,
    data_type: DataType,
    interleave: Interleave,
    big_endian: bool,
    wavelengths_nm: Vec<f64>,
    fwhm_nm: Option<Vec<f64>>,
    description: String,
    data_units: Option<String>,
}

impl EnviCube {
    /// Open a cube given its header (`NAME.hdr`, data beside it, see the
    /// module notes) or its data file (header `NAME.hdr`, or `DATA.hdr` if
    /// that exists). Checks the header and that the data file is long
    /// enough.
    pub fn open(hdr_or_bsq: &Path) -> Result<EnviCube> {
        Self::open_with(hdr_or_bsq, None)
    }

    /// [`EnviCube::open`], with the band centres (nm) given for a header
    /// that has neither `wavelength` nor numbers in its `band names`, or to
    /// replace them.
    pub fn open_with(hdr_or_bsq: &Path, wavelengths_nm: Option<&[f64]>) -> Result<EnviCube> {
        let is_hdr = hdr_or_bsq
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("hdr"));
        let (header_path, data_path) = if is_hdr {
            (hdr_or_bsq.to_path_buf(), PathBuf::new())
        } else {
            let mut appended = hdr_or_bsq.as_os_str().to_owned();
            appended.push(".hdr");
            let appended = PathBuf::from(appended);
            let header = if appended.exists() {
                appended
            } else {
                hdr_or_bsq.with_extension("hdr")
            };
            (header, hdr_or_bsq.to_path_buf())
        };
        let text = read_header_text(&header_path)?;
        let fields = parse_fields(&header_path, &text)?;
        let h = Header {
            path: &header_path,
            fields,
        };

        let samples = h.positive("samples")?;
        let lines = h.positive("lines")?;
        let bands = h.positive("bands")?;
        let header_offset = match h.get("header offset") {
            None => 0,
            Some(_) => h.whole("header offset")? as u64,
        };
        let data_type = h.data_type()?;
        let interleave = h.interleave()?;
        let big_endian = h.big_endian()?;
        let data_path = if is_hdr {
            find_data_file(&header_path, interleave)?
        } else {
            data_path
        };
        let scale = h.wavelength_scale()?;
        let wavelengths_nm: Vec<f64> = match wavelengths_nm {
            Some(given) if given.len() != bands => {
                return Err(Error::invalid(
                    "--wavelengths",
                    format!("has {} values but the cube has {bands} bands", given.len()),
                ))
            }
            Some(given) => given.to_vec(),
            None => match h.list("wavelength", bands)? {
                Some(w) => w.into_iter().map(|w| w * scale).collect(),
                None => h.band_name_wavelengths(bands, scale)?.ok_or_else(|| {
                    Error::data(
                        &header_path,
                        None,
                        "wavelength",
                        "missing: a spectral cube needs band wavelengths (a wavelength list, numbers in band names, or --wavelengths)",
                    )
                })?,
            },
        };
        let fwhm_nm = h
            .list("fwhm", bands)?
            .map(|v| v.into_iter().map(|w| w * scale).collect());
        let description = h
            .get("description")
            .map(|(v, _)| v.to_string())
            .unwrap_or_default();
        let data_units = h.get("data units").map(|(v, _)| v.to_string());

        let file = File::open(&data_path).map_err(|e| Error::io(&data_path, "open", e))?;
        let len = file
            .metadata()
            .map_err(|e| Error::io(&data_path, "stat", e))?
            .len();
        let needed = (samples as u64)
            .checked_mul(lines as u64)
            .and_then(|n| n.checked_mul(bands as u64))
            .and_then(|n| n.checked_mul(data_type.bytes() as u64))
            .and_then(|n| n.checked_add(header_offset))
            .filter(|&n| usize::try_from(n).is_ok())
            .ok_or_else(|| {
                Error::data(
                    &header_path,
                    None,
                    "samples",
                    format!("{samples} x {lines} x {bands} values overflow a file size"),
                )
            })?;
        if len != needed {
            // Longer is as wrong as shorter: the header describes another
            // file, or the data was appended to.
            return Err(Error::data(
                &data_path,
                None,
                "size",
                format!(
                    "holds {len} bytes but the header's {samples} x {lines} x {bands} values of {} bytes need {needed}",
                    data_type.bytes()
                ),
            ));
        }
        Ok(EnviCube {
            header_path,
            data_path,
            file,
            samples,
            lines,
            bands,
            header_offset,
            data_type,
            interleave,
            big_endian,
            wavelengths_nm,
            fwhm_nm,
            description,
            data_units,
        })
    }

    /// Pixels per line.
    pub fn samples(&self) -> usize {
        self.samples
    }

    /// Lines.
    pub fn lines(&self) -> usize {
        self.lines
    }

    /// Bands.
    pub fn bands(&self) -> usize {
        self.bands
    }

    /// Band centres in nm (converted if the header gave micrometres).
    pub fn wavelengths_nm(&self) -> &[f64] {
        &self.wavelengths_nm
    }

    /// Band widths (FWHM) in nm, if the header has them.
    pub fn fwhm_nm(&self) -> Option<&[f64]> {
        self.fwhm_nm.as_deref()
    }

    /// The header's description (empty if none).
    pub fn description(&self) -> &str {
        &self.description
    }

    /// The header's `data units`, if present.
    pub fn data_units(&self) -> Option<&str> {
        self.data_units.as_deref()
    }

    /// The header file.
    pub fn header_path(&self) -> &Path {
        &self.header_path
    }

    /// The data file.
    pub fn data_path(&self) -> &Path {
        &self.data_path
    }

    /// How the data file orders the values.
    pub fn interleave(&self) -> Interleave {
        self.interleave
    }

    /// How each value is stored.
    pub fn data_type(&self) -> DataType {
        self.data_type
    }

    /// The spectrum of pixel (`x`, `y`): one value per band (one small read
    /// per band, as BSQ stores a pixel's bands a whole band apart).
    pub fn spectrum(&self, x: usize, y: usize) -> Result<Vec<f32>> {
        if x >= self.samples || y >= self.lines {
            return Err(Error::data(
                &self.data_path,
                None,
                "pixel",
                format!(
                    "({x}, {y}) lies outside the {} x {} cube",
                    self.samples, self.lines
                ),
            ));
        }
        if self.interleave == Interleave::Bip {
            let mut v = vec![0f32; self.bands];
            self.read_values(
                (y as u64 * self.samples as u64 + x as u64) * self.bands as u64,
                &mut v,
            )?;
            return Ok(v);
        }
        (0..self.bands)
            .map(|b| {
                let mut v = [0f32];
                self.read_run(b, y, x, &mut v)?;
                Ok(v[0])
            })
            .collect()
    }

    /// Band `b` (0-based), all pixels in row order.
    pub fn band(&self, b: usize) -> Result<Vec<f32>> {
        self.band_rows(b, 0, self.lines)
    }

    /// Lines `y0..y0+h` of band `b`, in row order: lets a caller stream
    /// through a band too large to hold.
    pub fn band_rows(&self, b: usize, y0: usize, h: usize) -> Result<Vec<f32>> {
        if b >= self.bands {
            return Err(Error::data(
                &self.data_path,
                None,
                "band",
                format!("{b} is not below the cube's {} bands", self.bands),
            ));
        }
        if y0.checked_add(h).is_none_or(|end| end > self.lines) {
            return Err(Error::data(
                &self.data_path,
                None,
                "lines",
                format!(
                    "{y0}..{y0}+{h} is not within the cube's {} lines",
                    self.lines
                ),
            ));
        }
        let mut values = vec![0f32; h * self.samples];
        if self.interleave == Interleave::Bsq {
            // A band's lines are contiguous: one read.
            self.read_values(self.element(b, y0, 0), &mut values)?;
        } else {
            for (row, out) in values.chunks_mut(self.samples).enumerate() {
                self.read_run(b, y0 + row, 0, out)?;
            }
        }
        Ok(values)
    }

    /// The window `x0..x0+w` x `y0..y0+h` of band `b`, in row order (one
    /// positioned read per line).
    pub fn window(&self, b: usize, x0: usize, y0: usize, w: usize, h: usize) -> Result<Vec<f32>> {
        let inside = |start: usize, len: usize, size: usize| {
            start.checked_add(len).is_some_and(|end| end <= size)
        };
        if b >= self.bands || !inside(x0, w, self.samples) || !inside(y0, h, self.lines) {
            return Err(Error::data(
                &self.data_path,
                None,
                "window",
                format!(
                    "band {b}, {w} x {h} at ({x0}, {y0}) is not within the {} x {} x {} cube",
                    self.samples, self.lines, self.bands
                ),
            ));
        }
        let mut values = vec![0f32; w * h];
        for (row, out) in values.chunks_mut(w.max(1)).enumerate().take(h) {
            self.read_run(b, y0 + row, x0, out)?;
        }
        Ok(values)
    }

    /// The band whose centre is nearest `nm` (the first of equals; band 0
    /// for a NaN).
    pub fn band_index_nearest(&self, nm: f64) -> usize {
        self.wavelengths_nm
            .iter()
            .enumerate()
            .min_by(|a, b| (a.1 - nm).abs().total_cmp(&(b.1 - nm).abs()))
            .map_or(0, |(i, _)| i)
    }

    /// Element index of (x, y) in band b.
    fn element(&self, b: usize, y: usize, x: usize) -> u64 {
        self.interleave
            .element([self.samples, self.lines, self.bands], b, y, x)
    }

    /// `out.len()` values of band `b` on line `y` from column `x0`.
    fn read_run(&self, b: usize, y: usize, x0: usize, out: &mut [f32]) -> Result<()> {
        if self.interleave != Interleave::Bip {
            return self.read_values(self.element(b, y, x0), out);
        }
        // A line's pixels hold every band: read them all, keep one.
        let nb = self.bands;
        let mut all = vec![0f32; out.len() * nb];
        self.read_values(self.element(0, y, x0), &mut all)?;
        for (o, v) in out.iter_mut().zip(all.iter().skip(b).step_by(nb)) {
            *o = *v;
        }
        Ok(())
    }

    /// `out.len()` consecutive values from `element`, as f32.
    fn read_values(&self, element: u64, out: &mut [f32]) -> Result<()> {
        let width = self.data_type.bytes();
        let offset = self.header_offset + element * width as u64;
        if self.data_type == DataType::F32 && !self.big_endian {
            crate::output::read_exact_at(&self.file, bytemuck::cast_slice_mut(out), offset)
                .map_err(|e| Error::io(&self.data_path, "read", e))?;
            for v in out.iter_mut() {
                *v = f32::from_bits(u32::from_le(v.to_bits()));
            }
            return Ok(());
        }
        let mut bytes = vec![0u8; out.len() * width];
        crate::output::read_exact_at(&self.file, &mut bytes, offset)
            .map_err(|e| Error::io(&self.data_path, "read", e))?;
        for (o, b) in out.iter_mut().zip(bytes.chunks_exact(width)) {
            *o = self.data_type.decode(b, self.big_endian);
        }
        Ok(())
    }
}

/// The data file of the cube whose header is `header`: the first that
/// exists of `NAME.<interleave>`, `NAME.bsq`, `.bil`, `.bip`, `.img`,
/// `.dat`, `.raw` and `NAME`.
fn find_data_file(header: &Path, interleave: Interleave) -> Result<PathBuf> {
    let mut tried = Vec::new();
    for ext in [
        interleave.extension(),
        "bsq",
        "bil",
        "bip",
        "img",
        "dat",
        "raw",
        "",
    ] {
        let path = if ext.is_empty() {
            header.with_extension("")
        } else {
            header.with_extension(ext)
        };
        if path.is_file() {
            return Ok(path);
        }
        if !tried.contains(&path) {
            tried.push(path);
        }
    }
    Err(Error::data(
        header,
        None,
        "data file",
        format!(
            "none beside the header (tried {})",
            tried
                .iter()
                .map(|p| p.display().to_string())
                .collect::<Vec<_>>()
                .join(", ")
        ),
    ))
}

fn read_header_text(path: &Path) -> Result<String> {
    let file = File::open(path).map_err(|e| Error::io(path, "open", e))?;
    let mut bytes = Vec::new();
    file.take(MAX_HEADER_BYTES + 1)
        .read_to_end(&mut bytes)
        .map_err(|e| Error::io(path, "read", e))?;
    if bytes.len() as u64 > MAX_HEADER_BYTES {
        return Err(Error::data(
            path,
            None,
            "header",
            format!("is larger than {MAX_HEADER_BYTES} bytes: not an ENVI header"),
        ));
    }
    String::from_utf8(bytes)
        .map_err(|_| Error::data(path, None, "header", "is not text: not an ENVI header"))
}

/// A `key = value` of the header: lower-cased key, value without braces,
/// and the 1-based line the key is on.
type Field = (String, String, usize);

/// Split a header into fields. Values in braces may span lines; `;` starts
/// a comment line.
fn parse_fields(path: &Path, text: &str) -> Result<Vec<Field>> {
    let mut lines = text.lines().enumerate().map(|(i, l)| (i + 1, l));
    match lines.by_ref().find(|(_, l)| !l.trim().is_empty()) {
        Some((_, l)) if l.trim() == "ENVI" => {}
        found => {
            return Err(Error::data(
                path,
                found.map(|(n, _)| n),
                "header",
                "does not start with 'ENVI'",
            ))
        }
    }
    let mut fields: Vec<Field> = Vec::new();
    while let Some((n, line)) = lines.next() {
        let line = line.trim();
        if line.is_empty() || line.starts_with(';') {
            continue;
        }
        let Some((key, rest)) = line.split_once('=') else {
            return Err(Error::data(
                path,
                Some(n),
                "header",
                format!("expected 'key = value', got '{line}'"),
            ));
        };
        let key = key.trim().to_ascii_lowercase();
        let rest = rest.trim();
        let value = if let Some(open) = rest.strip_prefix('{') {
            let mut body = open.to_string();
            while !body.contains('}') {
                let Some((_, more)) = lines.next() else {
                    return Err(Error::data(path, Some(n), &key, "'{' is never closed"));
                };
                body.push('\n');
                body.push_str(more);
            }
            let (inside, after) = body.split_once('}').unwrap_or((&body, ""));
            // Values never nest braces: a second '{' first means this one
            // was left open and swallowed the next field.
            if inside.contains('{') {
                return Err(Error::data(path, Some(n), &key, "'{' is never closed"));
            }
            if !after.trim().is_empty() {
                return Err(Error::data(
                    path,
                    Some(n),
                    &key,
                    format!("unexpected '{}' after the closing '}}'", after.trim()),
                ));
            }
            inside.trim().to_string()
        } else {
            rest.to_string()
        };
        if key.is_empty() {
            return Err(Error::data(path, Some(n), "header", "a value has no key"));
        }
        if fields.iter().any(|(k, _, _)| *k == key) {
            return Err(Error::data(path, Some(n), &key, "appears twice"));
        }
        fields.push((key, value, n));
    }
    Ok(fields)
}

/// Typed access to parsed header fields, with errors naming file, line and field.
struct Header<'a> {
    path: &'a Path,
    fields: Vec<Field>,
}

impl Header<'_> {
    /// `data type`: the four ENVI codes the reader takes.
    fn data_type(&self) -> Result<DataType> {
        Ok(match self.required("data type")? {
            ("2", _) => DataType::I16,
            ("12", _) => DataType::U16,
            ("4", _) => DataType::F32,
            ("5", _) => DataType::F64,
            (v, line) => {
                return Err(Error::data(
                    self.path,
                    Some(line),
                    "data type",
                    format!(
                "is '{v}': supported are 2 (int16), 12 (uint16), 4 (float32) and 5 (float64)"
            ),
                ))
            }
        })
    }

    /// `interleave`: bsq, bil or bip.
    fn interleave(&self) -> Result<Interleave> {
        let (v, line) = self.required("interleave")?;
        Interleave::parse(v).ok_or_else(|| {
            Error::data(
                self.path,
                Some(line),
                "interleave",
                format!("is '{v}': bsq, bil or bip"),
            )
        })
    }

    /// `byte order`: 0 (little-endian, the default) or 1.
    fn big_endian(&self) -> Result<bool> {
        Ok(match self.get("byte order") {
            None | Some(("0", _)) => false,
            Some(("1", _)) => true,
            Some((v, line)) => {
                return Err(Error::data(
                    self.path,
                    Some(line),
                    "byte order",
                    format!("is '{v}': 0 (little-endian) or 1 (big-endian)"),
                ))
            }
        })
    }

    /// `wavelength units`: the factor to nanometres.
    fn wavelength_scale(&self) -> Result<f64> {
        Ok(match self.get("wavelength units") {
            None => 1.0,
            Some((v, line)) => match v.to_ascii_lowercase().as_str() {
                "nanometers" | "nm" => 1.0,
                "micrometers" | "microns" | "um" => 1000.0,
                _ => {
                    return Err(Error::data(
                        self.path,
                        Some(line),
                        "wavelength units",
                        format!("'{v}' is not Nanometers or Micrometers"),
                    ))
                }
            },
        })
    }
    fn get(&self, key: &str) -> Option<(&str, usize)> {
        self.fields
            .iter()
            .find(|(k, _, _)| k == key)
            .map(|(_, v, n)| (v.as_str(), *n))
    }

    fn required(&self, key: &str) -> Result<(&str, usize)> {
        self.get(key)
            .ok_or_else(|| Error::data(self.path, None, key, "missing"))
    }

    fn whole(&self, key: &str) -> Result<usize> {
        let (v, n) = self.required(key)?;
        v.parse::<usize>().map_err(|_| {
            Error::data(
                self.path,
                Some(n),
                key,
                format!("expected a whole number, got '{v}'"),
            )
        })
    }

    fn positive(&self, key: &str) -> Result<usize> {
        match self.whole(key)? {
            0 => Err(Error::data(
                self.path,
                self.get(key).map(|(_, n)| n),
                key,
                "must be at least 1",
            )),
            v => Ok(v),
        }
    }

    /// Band centres (nm) from the first number in each of `band names`
    /// that is followed by a unit (nm, um) or is the whole name (then in
    /// the header's wavelength units, `scale`), or `None` without band
    /// names or such a number in each ("Band 3" names a band, not a
    /// wavelength).
    fn band_name_wavelengths(&self, count: usize, scale: f64) -> Result<Option<Vec<f64>>> {
        let Some((v, n)) = self.get("band names") else {
            return Ok(None);
        };
        let names: Vec<&str> = v.split(',').map(str::trim).collect();
        if names.len() != count {
            return Err(Error::data(
                self.path,
                Some(n),
                "band names",
                format!("has {} names but bands = {count}", names.len()),
            ));
        }
        let number = |name: &str| -> Option<f64> {
            let start = name.find(|c: char| c.is_ascii_digit())?;
            let rest = &name[start..];
            let end = rest
                .find(|c: char| !(c.is_ascii_digit() || c == '.'))
                .unwrap_or(rest.len());
            let x: f64 = rest[..end].parse().ok()?;
            let lower = rest[end..].trim_start().to_ascii_lowercase();
            let micro =
                lower.starts_with("um") || lower.starts_with("µm") || lower.starts_with("micro");
            let nano = lower.starts_with("nm") || lower.starts_with("nano");
            // A bare number, or one with a unit: "Band 3" numbers bands.
            if micro {
                Some(x * 1000.0)
            } else if nano {
                Some(x)
            } else {
                (name.trim() == &rest[..end]).then_some(x * scale)
            }
        };
        Ok(names
            .iter()
            .map(|name| number(name).filter(|x| *x > 0.0 && x.is_finite()))
            .collect())
    }

    /// A `{a, b, ...}` list of finite numbers with exactly `count` entries,
    /// or `None` if the field is absent.
    fn list(&self, key: &str, count: usize) -> Result<Option<Vec<f64>>> {
        let Some((v, n)) = self.get(key) else {
            return Ok(None);
        };
        let values = v
            .split(',')
            .map(|s| s.trim())
            .enumerate()
            .map(|(i, s)| {
                s.parse::<f64>()
                    .ok()
                    .filter(|x| x.is_finite())
                    .ok_or_else(|| {
                        Error::data(
                            self.path,
                            Some(n),
                            format!("{key}[{i}]"),
                            format!("expected a number, got '{s}'"),
                        )
                    })
            })
            .collect::<Result<Vec<f64>>>()?;
        if values.len() != count {
            return Err(Error::data(
                self.path,
                Some(n),
                key,
                format!("has {} values but bands = {count}", values.len()),
            ));
        }
        Ok(Some(values))
    }
}
