//! The emission inputs of a scene, for the provenance of its photon maps.
//!
//! Hashed: every validated value emission reads, after defaults and
//! overrides are applied (seed, photon count, band grid, sun, sky, surface,
//! domain, water and its phase functions, floor and target reflectances,
//! the geometry's triangles, tally depths, `store_direct`, `upward_split`), and the bytes of
//! every file the scene names. Not hashed: `[sensor]`, `[[radiometer]]`,
//! `[estimate]` and the scene's name, which do not change a single photon.
//!
//! Values are hashed through their `Debug` form, which prints every float
//! exactly (shortest round-trip digits): two scenes that differ only in how
//! they spell a value (a default written out, `1.0` for `1`) hash alike.

use super::Scene;
use crate::error::{Error, Result};
use crate::optics::inelastic::Kind;
use crate::provenance::{sha256_hex, ProvenanceBuilder};

impl Scene {
    /// The digest parts and readable record of everything emission reads.
    pub fn emission_inputs(&self) -> Result<ProvenanceBuilder> {
        let mut b = ProvenanceBuilder::new();
        b.note("scene", &self.name)
            .value("photons", self.photons)
            .value("bands", self.bands.len())
            .value("seed", self.seed)
            .value("store_direct", self.store_direct)
            .value("upward_split", self.upward_split)
            .value("tally_depths_m", &self.tally_depths);
        // Only where paths split, so that the maps of scenes without
        // targets keep their digests.
        if !self.split_footprints.is_empty() {
            b.value("target_split", self.target_split);
        }
        // Only when on, so that the maps of scenes without it keep their
        // digests.
        if let Some(inelastic) = &self.inelastic {
            for p in &inelastic.processes {
                match p.kind {
                    Kind::Raman => b.value("raman", true),
                    Kind::Chlorophyll => b.value(
                        "chl_quantum_yield",
                        p.scale.iter().fold(0.0, |m: f64, &x| m.max(x)),
                    ),
                    Kind::Cdom => b.value("cdom_fluorescence", true),
                };
            }
        }
        let parts: [(&str, String); 12] = [
            ("band_grid", format!("{:?}", self.bands)),
            ("sun", format!("{:?}", self.sun)),
            ("sky", format!("{:?}", self.sky)),
            ("surface", format!("{:?}", self.surface)),
            ("water_index", format!("{:?}", self.water_index)),
            ("domain", format!("{:?}", self.domain)),
            ("water", format!("{:?}", self.water)),
            ("particle_phase", format!("{:?}", self.particle_phase)),
            ("water_phase", format!("{:?}", self.water_phase)),
            ("bottom", format!("{:?}", self.bottom)),
            (
                "target_reflectance",
                format!("{:?}", self.target_reflectance),
            ),
            ("crate_version", env!("CARGO_PKG_VERSION").to_string()),
        ];
        for (name, text) in &parts {
            b.part(name, text.as_bytes());
        }
        let mut geometry = Vec::new();
        self.geometry
            .digest_into(&mut |bytes| geometry.extend_from_slice(bytes));
        b.part("geometry", &geometry);
        let mut files = Vec::new();
        for path in &self.inputs {
            let bytes = std::fs::read(path).map_err(|e| Error::io(path, "read", e))?;
            b.part(&format!("file {}", path.display()), &bytes);
            files.push(serde_json::json!({
                "path": path.display().to_string(),
                "bytes": bytes.len(),
                "sha256": sha256_hex(&bytes),
            }));
        }
        b.note("files", files);
        Ok(b)
    }
}
