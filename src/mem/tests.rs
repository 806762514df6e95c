#[test]
fn reads_own_memory() {
    let peak = super::peak_rss_bytes().unwrap();
    let anon = super::rss_anon_bytes().unwrap();
    assert!(peak > 0 && anon > 0 && anon <= peak + (64 << 20));
}

/// The sampler sees an allocation that is held across a few samples, and
/// its anonymous peak lies between what was held and VmHWM.
#[test]
fn sampler_sees_a_held_allocation() {
    let sampler = super::PeakSampler::start();
    let size = 64usize << 20;
    let mut v = vec![1u8; size];
    // Touch every page, then hold it for several sample periods.
    for i in (0..size).step_by(4096) {
        v[i] = (i % 251) as u8;
    }
    std::thread::sleep(super::SAMPLE_PERIOD * 6);
    std::hint::black_box(&v);
    let peaks = sampler.finish();
    drop(v);
    // Other tests in this process may free memory meanwhile, but these
    // 64 MiB are resident while sampled.
    assert!(peaks.anon_bytes >= size as u64, "{peaks:?}");
    assert!(peaks.anon_bytes <= peaks.rss_bytes, "{peaks:?}");
    assert!(peaks.file_bytes > 0, "{peaks:?}");
}

/// The statistics of parts rendered apart combine as the assembly reports
/// them: cache counts add, resident bytes and memory peaks take the larger.
#[test]
fn parts_statistics_combine() {
    use crate::store::cache::CacheStats;
    let a = CacheStats {
        hits: 3,
        misses: 2,
        evictions: 1,
        decodes: 2,
        decoded_bytes: 100,
        resident_bytes: 50,
        peak_resident_bytes: 70,
    };
    let b = CacheStats {
        hits: 10,
        misses: 5,
        evictions: 4,
        decodes: 5,
        decoded_bytes: 400,
        resident_bytes: 20,
        peak_resident_bytes: 90,
    };
    let mut sum = CacheStats::default();
    sum += &a;
    sum += &b;
    assert_eq!(
        (
            sum.hits,
            sum.misses,
            sum.evictions,
            sum.decodes,
            sum.decoded_bytes
        ),
        (13, 7, 5, 7, 500)
    );
    assert_eq!((sum.resident_bytes, sum.peak_resident_bytes), (50, 90));
    let mut peaks = super::MemoryPeaks {
        anon_bytes: 5,
        file_bytes: 9,
        rss_bytes: 12,
    };
    peaks.max_with(&super::MemoryPeaks {
        anon_bytes: 7,
        file_bytes: 3,
        rss_bytes: 12,
    });
    assert_eq!(
        (peaks.anon_bytes, peaks.file_bytes, peaks.rss_bytes),
        (7, 9, 12)
    );
}
