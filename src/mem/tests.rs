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
