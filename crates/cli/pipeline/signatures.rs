//! What each source of a map sounds like (`ssl::signature`), from the recordings of the
//! stops that heard it: the array steered at the source's map position from each such stop
//! (the DoAs it explains say which), their features joined, the level made relative to the
//! map's loudest source.

use super::*;
use ssl::signature::{Heard, ListenConfig, Listener, Signature};

/// Each source's signature (in the map's order; `None` for a source no recording could be
/// steered at), its `level_db` relative to the loudest source's. `audio_of(k)` gives the
/// recording of stop `k`, heard by `array`.
///
/// # Errors
/// A recording that cannot be read, or whose channels are not the array's; named.
pub fn signatures(
    result: &MapResult,
    poses: &[Pose],
    array: &MicArray,
    audio_of: &(dyn Fn(usize) -> Result<Audio> + Sync),
) -> Result<Vec<Option<Signature>>> {
    let config = ListenConfig::default();
    // The stops that heard each source, once each.
    let mut heard_at: Vec<Vec<usize>> = result
        .sources
        .iter()
        .map(|s| {
            let mut v: Vec<usize> = s.rays.iter().map(|r| r.stop).collect();
            v.sort_unstable();
            v.dedup();
            v
        })
        .collect();
    heard_at
        .iter_mut()
        .for_each(|v| v.retain(|&k| k < poses.len()));
    let mut stops: Vec<usize> = heard_at.iter().flatten().copied().collect();
    stops.sort_unstable();
    stops.dedup();
    // Per stop, what each source heard there sounds like: one read of the recording.
    let per_stop: Vec<Vec<(usize, Heard, f64)>> = stops
        .par_iter()
        .map(|&k| -> Result<Vec<(usize, Heard, f64)>> {
            let audio = audio_of(k)?;
            let p = poses[k];
            // The recording's spectra and covariances once; a beam per source.
            let listener = Listener::new(&audio, array, &config)
                .with_context(|| format!("the signatures at stop {k}"))?;
            Ok(heard_at
                .iter()
                .enumerate()
                .filter(|(_, at)| at.binary_search(&k).is_ok())
                .map(|(i, _)| {
                    let s = &result.sources[i];
                    let azimuth = p.azimuth_to([s.x, s.y]);
                    let heard = listener.steer(azimuth.to_degrees(), 0.0);
                    (i, heard, (s.x - p.x).hypot(s.y - p.y))
                })
                .collect())
        })
        .collect::<Result<_>>()?;
    let mut by_source: Vec<Vec<(Heard, f64)>> = vec![Vec::new(); result.sources.len()];
    for (i, h, r) in per_stop.into_iter().flatten() {
        by_source[i].push((h, r));
    }
    let mut out: Vec<Option<Signature>> = by_source.iter().map(|h| Signature::of(h)).collect();
    let loudest = out
        .iter()
        .flatten()
        .map(|s| s.level_db)
        .fold(f64::NEG_INFINITY, f64::max);
    for s in out.iter_mut().flatten() {
        s.level_db -= loudest;
    }
    Ok(out)
}

/// The kind a scene's source has by its signal: a recording is speech (the scenes'
/// recordings are talkers), a voiced harmonic series with a steady pitch is tonal, and a
/// noise (white, pink, or with speech's long-term spectrum) is broadband.
pub fn scene_kind(spec: &sim::scene::SourceSpec) -> ssl::signature::Kind {
    use sim::signal::SignalKind;
    use ssl::signature::Kind;
    if spec.wav.is_some() {
        return Kind::Speech;
    }
    match spec.signal.unwrap_or_default() {
        SignalKind::Voiced => Kind::Tonal,
        SignalKind::WhiteNoise | SignalKind::PinkNoise | SignalKind::SpeechShaped => {
            Kind::Broadband
        }
    }
}

/// How many of a map's sources matched to a scene's places (within `within_m`, an optimal
/// assignment) have the kind of their place's signal, of how many matched: `(right,
/// matched)`. `kinds[i]` is the kind of the scene's room source `i` ([`scene_kind`]).
pub fn kinds_right(
    result: &MapResult,
    signatures: &[Option<Signature>],
    places: &[sim::scene::Place],
    kinds: &[ssl::signature::Kind],
    within_m: f64,
) -> (usize, usize) {
    let truth: Vec<[f64; 2]> = places.iter().map(|p| [p.pos[0], p.pos[1]]).collect();
    let mut right = 0;
    let mut matched = 0;
    for (j, i) in asm::ospa::pairs(&result.positions(), &truth, within_m) {
        if let (Some(sig), Some(&kind)) = (&signatures[j], kinds.get(places[i].source)) {
            matched += 1;
            right += usize::from(sig.kind == kind);
        }
    }
    (right, matched)
}
