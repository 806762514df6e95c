//! ENVI radiance cubes: a tile-by-tile writer and a lazy reader.
//!
//! Format: an ENVI Standard text header `NAME.hdr` beside a headerless
//! binary `NAME.bsq` of 32-bit IEEE floats, little-endian (`data type = 4`,
//! `byte order = 0`), band-sequential: the value of pixel (x, y) in band b
//! sits at element `(b * lines + y) * samples + x`. BSQ is what most
//! remote-sensing software reads fastest band by band, and it lets the reader
//! serve one band with a single read.
//!
//! The writer never holds the cube: [`EnviWriter::create`] pre-sizes the data
//! file under a temporary name and [`EnviWriter::write_tile`] scatters each
//! tile (laid out `[y][x][band]`, as a renderer produces spectra) into its
//! BSQ positions with positioned writes, so tiles may arrive in any order and
//! from several threads at once. [`EnviWriter::finish`] syncs and renames the
//! data file and then the header into place: a reader that finds the header
//! finds a complete cube, and a writer dropped without `finish` (a crash, an
//! error in another tile) leaves neither final name behind.
//!
//! [`EnviCube`] (in `envi/reader.rs`, its header in `envi/header.rs`) reads such a cube, or an ENVI cube
//! of another software (BSQ, BIL or BIP; int16, uint16, float32 or float64;
//! either byte order), with positioned reads: a pixel's spectrum, a band,
//! or rows of a band, never the whole cube. Malformed headers are refused
//! with an error naming the file, the line and the field. The writer can
//! also lay the data out BIL or BIP ([`EnviWriter::create_interleaved`]),
//! always float32 little-endian.
//!
//! Not for: writing other data types or byte orders, nor for editing a
//! cube in place.

use std::path::{Path, PathBuf};

use crate::error::{Error, Result};
use crate::spectral::BandGrid;

mod header;
mod reader;
#[cfg(test)]
mod tests;

pub use reader::{DataType, EnviCube};

/// How an ENVI data file orders its values.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Interleave {
    /// Band-sequential: `[band][line][sample]`.
    Bsq,
    /// Band-interleaved by line: `[line][band][sample]`.
    Bil,
    /// Band-interleaved by pixel: `[line][sample][band]`.
    Bip,
}

impl Interleave {
    /// The header's `interleave` value (case-insensitive).
    pub fn parse(v: &str) -> Option<Interleave> {
        match v.to_ascii_lowercase().as_str() {
            "bsq" => Some(Interleave::Bsq),
            "bil" => Some(Interleave::Bil),
            "bip" => Some(Interleave::Bip),
            _ => None,
        }
    }

    /// The header value, also the data file's usual extension.
    pub fn extension(self) -> &'static str {
        match self {
            Interleave::Bsq => "bsq",
            Interleave::Bil => "bil",
            Interleave::Bip => "bip",
        }
    }

    /// Element index of sample `x` of line `y` in band `b` of a cube of
    /// `[samples, lines, bands]`.
    pub fn element(self, [samples, lines, bands]: [usize; 3], b: usize, y: usize, x: usize) -> u64 {
        let (s, l, n) = (samples as u64, lines as u64, bands as u64);
        let (b, y, x) = (b as u64, y as u64, x as u64);
        match self {
            Interleave::Bsq => (b * l + y) * s + x,
            Interleave::Bil => (y * n + b) * s + x,
            Interleave::Bip => (y * s + x) * n + b,
        }
    }
}

/// Bytes per stored value (32-bit float).
const VALUE_BYTES: u64 = 4;

/// What a cube holds: its size, its bands and a description.
#[derive(Clone, Debug, PartialEq)]
pub struct CubeSpec {
    /// Pixels per line (image width).
    pub samples: usize,
    /// Lines (image height).
    pub lines: usize,
    /// The bands, in file order; their centres and FWHMs go into the header.
    pub bands: BandGrid,
    /// Free text for the header's `description` (no braces).
    pub description: String,
    /// Units of the values, e.g. `W m-2 sr-1 nm-1` (no braces).
    pub data_units: String,
    /// The bands' names (`B1`, ...) for the header's `band names` and
    /// GDAL's band descriptions; empty: each band is named by its centre
    /// (`443 nm`).
    pub band_names: Vec<String>,
}

impl CubeSpec {
    /// The band centres as the header records them (each f32 centre in
    /// its shortest decimal form, read back as f64), so that a copy made
    /// from the spec names its bands as one made from the header would.
    pub fn header_wavelengths_nm(&self) -> Vec<f64> {
        self.bands
            .centers_nm()
            .iter()
            .map(|c| c.to_string().parse().unwrap_or(*c as f64))
            .collect()
    }

    /// Total values in the cube, or an error if it overflows the address space.
    fn values(&self) -> Result<u64> {
        (self.samples as u64)
            .checked_mul(self.lines as u64)
            .and_then(|n| n.checked_mul(self.bands.len() as u64))
            .filter(|n| n.checked_mul(VALUE_BYTES).is_some())
            .ok_or_else(|| {
                Error::invalid(
                    "cube size",
                    format!(
                        "{} x {} x {} values overflow a file size",
                        self.samples,
                        self.lines,
                        self.bands.len()
                    ),
                )
            })
    }

    fn validate(&self) -> Result<()> {
        if self.samples == 0 || self.lines == 0 {
            return Err(Error::invalid(
                "cube size",
                format!(
                    "samples and lines must be at least 1, got {} x {}",
                    self.samples, self.lines
                ),
            ));
        }
        for (field, text) in [
            ("description", &self.description),
            ("data units", &self.data_units),
        ] {
            // A brace would end the header's `{...}` value early, a line
            // break the header line.
            if text.contains(['{', '}', '\n', '\r']) {
                return Err(Error::invalid(
                    field,
                    "must not contain '{', '}' or a line break",
                ));
            }
        }
        if !self.band_names.is_empty() && self.band_names.len() != self.bands.len() {
            return Err(Error::invalid(
                "band names",
                format!(
                    "{} names for {} bands",
                    self.band_names.len(),
                    self.bands.len()
                ),
            ));
        }
        // A comma would split a name in the header's list.
        if let Some(bad) = self
            .band_names
            .iter()
            .find(|n| n.trim().is_empty() || n.contains(['{', '}', ',', '\n', '\r']))
        {
            return Err(Error::invalid(
                "band names",
                format!("'{bad}': a band name must be non-empty, without '{{', '}}', ',' or a line break"),
            ));
        }
        self.values().map(|_| ())
    }

    /// The ENVI header text for this cube, its data in `interleave` order.
    fn header_text(&self, interleave: Interleave) -> String {
        let list = |v: &[f32]| {
            v.iter()
                .map(|x| x.to_string())
                .collect::<Vec<_>>()
                .join(", ")
        };
        let names = self.names().join(", ");
        // Red, green and blue for viewers (1-based), when the grid spans them.
        let nearest = |target: f32| {
            let c = self.bands.centers_nm();
            let (i, d) = c
                .iter()
                .enumerate()
                .map(|(i, nm)| (i, (nm - target).abs()))
                .fold((0, f32::INFINITY), |m, x| if x.1 < m.1 { x } else { m });
            (d <= 20.0).then_some(i + 1)
        };
        let default_bands = match (nearest(640.0), nearest(550.0), nearest(460.0)) {
            (Some(r), Some(g), Some(b)) => format!("default bands = {{{r}, {g}, {b}}}\n"),
            _ => String::new(),
        };
        format!(
            "ENVI\n\
             description = {{{}}}\n\
             samples = {}\n\
             lines = {}\n\
             bands = {}\n\
             header offset = 0\n\
             file type = ENVI Standard\n\
             data type = 4\n\
             interleave = {}\n\
             byte order = 0\n\
             wavelength units = Nanometers\n\
             wavelength = {{{}}}\n\
             fwhm = {{{}}}\n\
             band names = {{{}}}\n\
             {}\
             sensor type = littoral simulation\n\
             data units = {}\n",
            self.description,
            self.samples,
            self.lines,
            self.bands.len(),
            interleave.extension(),
            list(self.bands.centers_nm()),
            list(self.bands.fwhm_nm()),
            names,
            default_bands,
            self.data_units,
        )
    }
}

impl CubeSpec {
    /// Each band's name: [`CubeSpec::band_names`], or its centre (`443 nm`).
    fn names(&self) -> Vec<String> {
        if self.band_names.len() == self.bands.len() {
            return self.band_names.clone();
        }
        self.bands
            .centers_nm()
            .iter()
            .map(|nm| format!("{nm} nm"))
            .collect()
    }

    /// GDAL's sidecar for the data file (`NAME.bsq.aux.xml`): each band's
    /// unit, which GDAL's ENVI driver (3.6) takes from no header key, only
    /// from this file's `UnitType`. It repeats the description GDAL makes
    /// from the header (`band name (wavelength Nanometers)`), since a band
    /// in the sidecar without one would lose it.
    fn gdal_sidecar(&self) -> String {
        let unit = xml_escape(&self.data_units);
        let mut x = String::from("<PAMDataset>\n");
        for (b, (nm, name)) in self.bands.centers_nm().iter().zip(self.names()).enumerate() {
            let name = xml_escape(&name);
            x.push_str(&format!(
                "  <PAMRasterBand band=\"{}\">\n    <Description>{name} ({nm} Nanometers)</Description>\n    <UnitType>{unit}</UnitType>\n  </PAMRasterBand>\n",
                b + 1
            ));
        }
        x.push_str("</PAMDataset>\n");
        x
    }
}

/// `text` with XML's special characters escaped.
fn xml_escape(text: &str) -> String {
    text.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// The two files of a cube on disk.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct CubeFiles {
    /// The ENVI header, `NAME.hdr`.
    pub hdr: PathBuf,
    /// The data, `NAME.bsq`.
    pub bsq: PathBuf,
}

/// Writes one ENVI BSQ cube tile by tile; see the module doc.
///
/// `Sync`: [`EnviWriter::write_tile`] takes `&self`, so render threads can
/// share one writer. Tiles must not overlap (overlapping writes race and the
/// last one wins per value).
#[derive(Debug)]
pub struct EnviWriter {
    spec: CubeSpec,
    // Temporary files delete themselves when dropped, which is what makes an
    // unfinished writer leave nothing behind.
    bsq: tempfile::NamedTempFile,
    hdr: tempfile::NamedTempFile,
    bsq_path: PathBuf,
    hdr_path: PathBuf,
    interleave: Interleave,
}

impl EnviWriter {
    /// Create `NAME.bsq` and `NAME.hdr` under temporary names in `dir`: the
    /// header is written now and the data file pre-sized (zero-filled,
    /// sparse) to the whole cube, ready for tiles. `name` is a plain file
    /// name without extension.
    pub fn create(dir: &Path, name: &str, spec: CubeSpec) -> Result<EnviWriter> {
        Self::create_with(dir, name, spec, &[])
    }

    /// [`EnviWriter::create`] with `extra` header lines (`key = value`,
    /// e.g. `map info`) after the standard ones.
    pub fn create_with(
        dir: &Path,
        name: &str,
        spec: CubeSpec,
        extra: &[String],
    ) -> Result<EnviWriter> {
        Self::create_interleaved(dir, name, spec, extra, Interleave::Bsq)
    }

    /// [`EnviWriter::create_with`], the data in `interleave` order in
    /// `NAME.bsq`, `NAME.bil` or `NAME.bip`.
    pub fn create_interleaved(
        dir: &Path,
        name: &str,
        spec: CubeSpec,
        extra: &[String],
        interleave: Interleave,
    ) -> Result<EnviWriter> {
        if let Some(bad) = extra
            .iter()
            .find(|l| !l.contains(" = ") || l.contains(['\n', '\r']))
        {
            return Err(Error::invalid(
                "header line",
                format!("'{bad}' is not one 'key = value' line"),
            ));
        }
        if name.is_empty()
            || name == "."
            || name == ".."
            || name.contains(['/', '\0'])
            || name.starts_with('.')
        {
            return Err(Error::invalid(
                "cube name",
                format!("'{name}' must be a plain file name (no '/', not starting with '.')"),
            ));
        }
        spec.validate()?;
        let bsq_path = dir.join(format!("{name}.{}", interleave.extension()));
        let hdr_path = dir.join(format!("{name}.hdr"));
        let temp = |path: &Path| {
            crate::output::temp_in(dir, ".littoral.", ".partial")
                .map_err(|e| Error::io(path, "create", e))
        };
        let bsq = temp(&bsq_path)?;
        let mut hdr = temp(&hdr_path)?;
        bsq.as_file()
            .set_len(spec.values()? * VALUE_BYTES)
            .map_err(|e| Error::io(&bsq_path, "pre-size", e))?;
        let mut text = spec.header_text(interleave);
        for line in extra {
            text.push_str(line);
            text.push('\n');
        }
        std::io::Write::write_all(&mut hdr, text.as_bytes())
            .map_err(|e| Error::io(&hdr_path, "write", e))?;
        Ok(EnviWriter {
            spec,
            bsq,
            hdr,
            bsq_path,
            hdr_path,
            interleave,
        })
    }

    /// The cube being written.
    pub fn spec(&self) -> &CubeSpec {
        &self.spec
    }

    /// Write the tile of pixels `x0..x0+w` by `y0..y0+h`. `values` holds
    /// `w * h * bands` values laid out `[y][x][band]` (band fastest).
    ///
    /// Each band of the tile is gathered into one buffer and written as one
    /// run per tile row — or as a single run when the tile spans whole lines,
    /// where a band's rows are contiguous in BSQ.
    pub fn write_tile(
        &self,
        x0: usize,
        y0: usize,
        w: usize,
        h: usize,
        values: &[f32],
    ) -> Result<()> {
        let (samples, lines, bands) = (self.spec.samples, self.spec.lines, self.spec.bands.len());
        let inside = |start: usize, len: usize, size: usize| {
            start.checked_add(len).is_some_and(|end| end <= size)
        };
        if w == 0 || h == 0 || !inside(x0, w, samples) || !inside(y0, h, lines) {
            return Err(Error::invalid(
                "tile",
                format!(
                    "{w} x {h} pixels at ({x0}, {y0}) is empty or does not fit a {samples} x {lines} cube"
                ),
            ));
        }
        // w * h * bands fits: the tile lies inside the cube, whose size was checked.
        if values.len() != w * h * bands {
            return Err(Error::invalid(
                "tile",
                format!(
                    "{w} x {h} pixels x {bands} bands needs {} values, got {}",
                    w * h * bands,
                    values.len()
                ),
            ));
        }
        let file = self.bsq.as_file();
        let dims = [samples, lines, bands];
        if self.interleave == Interleave::Bip {
            // A tile row is one run of [x][band] values.
            let le: Vec<f32> = values
                .iter()
                .map(|v| f32::from_bits(v.to_bits().to_le()))
                .collect();
            let row = w * bands;
            return le
                .chunks_exact(row)
                .enumerate()
                .try_for_each(|(dy, r)| {
                    let offset = Interleave::Bip.element(dims, 0, y0 + dy, x0) * VALUE_BYTES;
                    crate::output::write_all_at(file, bytemuck::cast_slice(r), offset)
                })
                .map_err(|e| Error::io(&self.bsq_path, "write", e));
        }
        let whole_lines = w == samples && self.interleave == Interleave::Bsq;
        let mut run: Vec<f32> = Vec::with_capacity(w * h);
        for b in 0..bands {
            run.clear();
            run.extend(
                values
                    .iter()
                    .skip(b)
                    .step_by(bands)
                    .map(|v| f32::from_bits(v.to_bits().to_le())),
            );
            let bytes: &[u8] = bytemuck::cast_slice(&run);
            let row_bytes = w * VALUE_BYTES as usize;
            let offset = |y: usize| self.interleave.element(dims, b, y, x0) * VALUE_BYTES;
            let result = if whole_lines {
                crate::output::write_all_at(file, bytes, offset(y0))
            } else {
                bytes
                    .chunks_exact(row_bytes)
                    .enumerate()
                    .try_for_each(|(dy, row)| {
                        crate::output::write_all_at(file, row, offset(y0 + dy))
                    })
            };
            result.map_err(|e| Error::io(&self.bsq_path, "write", e))?;
        }
        Ok(())
    }

    /// Sync both files and rename them to their final names, the data file
    /// first and the header last, so a header always describes a complete
    /// data file. Existing files of the same names are replaced.
    pub fn finish(self) -> Result<CubeFiles> {
        let EnviWriter {
            spec,
            bsq,
            hdr,
            bsq_path,
            hdr_path,
            ..
        } = self;
        for (temp, path) in [(&bsq, &bsq_path), (&hdr, &hdr_path)] {
            crate::output::finalize(temp, path)?;
        }
        crate::output::rename_into_place(bsq, &bsq_path)?;
        let mut sidecar = bsq_path.clone().into_os_string();
        sidecar.push(".aux.xml");
        crate::output::write_atomic(Path::new(&sidecar), spec.gdal_sidecar().as_bytes())?;
        crate::output::rename_into_place(hdr, &hdr_path)?;
        Ok(CubeFiles {
            hdr: hdr_path,
            bsq: bsq_path,
        })
    }
}
