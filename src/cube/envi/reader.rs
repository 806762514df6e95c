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
use std::path::{Path, PathBuf};

use super::header::{parse_fields, read_header_text, Header};
use super::Interleave;
use crate::error::{Error, Result};

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
