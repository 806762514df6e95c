//! Splitting a cell that outgrew a tile: two passes over its photons
//! (those buffered and those spilled), the first for an order-independent
//! sample that picks the plane, the second dealing the photons to the two
//! halves, which spill as they fill.

use super::{CellBuf, MapWriter, STAGED, WRITER_FIXED_BYTES};
use crate::error::{Error, Result};
use crate::rng::mix64;
use crate::store::codec::StagedPhoton;
use crate::store::spill::Fetched;

impl MapWriter {
    /// Split an overfull cell in two, streaming, without holding it in
    /// memory decoded: its spilled frames are read from `fetched` when
    /// given (all of them, undecoded), else from the scratch file.
    ///
    /// One function of about 130 lines: its two passes share the cell's
    /// buffers, the fetched frames and the writer's budget charges, and
    /// each pass is a closure over the same frame loop; split apart, the
    /// pieces would hand that state back and forth.
    pub(super) fn split(
        &mut self,
        mut cell: CellBuf,
        fetched: Option<&Fetched>,
        frame_buf: &mut Vec<StagedPhoton>,
    ) -> Result<(CellBuf, CellBuf)> {
        // Pass 1: an order-independent sample (chosen by a hash of the
        // record) and the least and greatest records.
        let rate = cell.count.div_ceil(32_768).next_power_of_two();
        let mut sample: Vec<[u64; 3]> = Vec::new();
        let (mut least, mut most) = ([u64::MAX; 3], [0u64; 3]);
        let mut take = |p: &StagedPhoton| {
            let key = p.key();
            least = least.min(key);
            most = most.max(key);
            if mix64(key[0] ^ mix64(key[1] ^ mix64(key[2]))) & (rate - 1) == 0 {
                sample.push(key);
            }
        };
        match fetched {
            Some(fetched) => {
                for (body, count) in fetched.bodies() {
                    self.scratch().decode(body, count, frame_buf)?;
                    frame_buf.iter().for_each(&mut take);
                }
            }
            None => self
                .scratch()
                .for_each_frame(cell.last_frame, frame_buf, |records| {
                    records.iter().for_each(&mut take)
                })?,
        }
        cell.chunks.iter().flatten().for_each(&mut take);

        // The plane: the sample median on the longest axis that separates it.
        let extent = cell.bounds.max - cell.bounds.min;
        let mut axes = [0usize, 1, 2];
        axes.sort_by(|&a, &b| extent[b].total_cmp(&extent[a]));
        let mut plane = None;
        for axis in axes {
            let mut v: Vec<f32> = sample
                .iter()
                .map(|k| bytemuck::cast::<_, StagedPhoton>(*k).photon.position[axis])
                .collect();
            if v.is_empty() {
                break;
            }
            let mid = v.len() / 2;
            let (_, &mut median, _) = v.select_nth_unstable_by(mid, f32::total_cmp);
            let below = v.iter().filter(|&&x| x < median).count();
            if below > 0 {
                plane = Some((axis, median));
                break;
            }
            // Everything at or above the median: cut just above the minimum
            // if that separates anything.
            let above_min = v.iter().filter(|&&x| x > median).count();
            if above_min > 0 {
                plane = Some((axis, next_after(median)));
                break;
            }
        }
        // All sampled positions coincide: halve in the records' own order
        // instead, at the sample's median record (below it, or up to it when
        // it is the least). Only when every record is the same are they
        // dealt out in turn; which copy goes where cannot change the map.
        let pivot = match sample.len() {
            0 => least,
            n => *sample.select_nth_unstable(n / 2).1,
        };
        let turn = std::cell::Cell::new(0u64);
        let route = |p: &StagedPhoton| match plane {
            Some((axis, value)) => p.photon.position[axis] < value,
            None if least == most => {
                turn.set(turn.get() + 1);
                turn.get() & 1 == 0
            }
            None if pivot > least => p.key() < pivot,
            None => p.key() <= pivot,
        };

        // Pass 2: route every photon to a child, spilling children as they grow.
        let mut split = Split {
            route: &route,
            kids: [CellBuf::new(), CellBuf::new()],
            kid_bytes: [0; 2],
            limit: (self.plan.budget - WRITER_FIXED_BYTES) / 16,
            chunk_records: self.plan.chunk_records,
        };
        // Children spill to the end of the scratch file while the parent's
        // (immutable) frames are read back.
        let mut next = cell.last_frame.take();
        let mut bodies = fetched.map(Fetched::bodies);
        loop {
            match bodies.as_mut() {
                Some(bodies) => match bodies.next() {
                    Some((body, count)) => self.scratch().decode(body, count, frame_buf)?,
                    None => break,
                },
                None => match next {
                    Some(f) => next = self.scratch().read(f, frame_buf)?,
                    None => break,
                },
            }
            let batch = std::mem::take(frame_buf);
            self.route(&batch, &mut split)?;
            *frame_buf = batch;
        }
        for chunk in std::mem::take(&mut cell.chunks) {
            self.route(&chunk, &mut split)?;
            self.buffered -= (chunk.capacity() * STAGED) as u64;
        }
        let (kids, kid_bytes) = (split.kids, split.kid_bytes);
        let [left, right] = kids;
        self.buffered += kid_bytes[0] + kid_bytes[1];
        if left.count + right.count != cell.count {
            return Err(Error::io(
                &self.path,
                "split a cell",
                std::io::Error::new(
                    std::io::ErrorKind::InvalidData,
                    format!(
                        "{} photons came back from the scratch file as {} and {}",
                        cell.count, left.count, right.count
                    ),
                ),
            ));
        }
        debug_assert!(left.count > 0 && right.count > 0);
        Ok((left, right))
    }

    /// Send `photons` to the children of `split`, spilling a child whose
    /// buffers pass the limit.
    fn route(&mut self, photons: &[StagedPhoton], split: &mut Split) -> Result<()> {
        for p in photons {
            let k = if (split.route)(p) { 0 } else { 1 };
            let kid = &mut split.kids[k];
            if kid.push(p, split.chunk_records) {
                split.kid_bytes[k] += (split.chunk_records * STAGED) as u64;
            }
            if split.kid_bytes[k] > split.limit {
                kid.spill(self.scratch())?;
                split.kid_bytes[k] = 0;
            }
        }
        Ok(())
    }
}

/// A cell being split in two: which side each photon goes to, and the two
/// children with their buffered bytes.
struct Split<'r> {
    route: &'r dyn Fn(&StagedPhoton) -> bool,
    kids: [CellBuf; 2],
    kid_bytes: [u64; 2],
    /// Buffered bytes at which a child spills.
    limit: u64,
    chunk_records: usize,
}

fn next_after(x: f32) -> f32 {
    let b = x.to_bits();
    f32::from_bits(if x >= 0.0 { b + 1 } else { b - 1 })
}
