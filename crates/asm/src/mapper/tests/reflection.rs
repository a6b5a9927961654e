//! Heard by reflection ([`IasmConfig::reflections`]): the place where a source's
//! reflections in the map's walls cross is no source, and a source its own rays fit is.

use super::*;

/// A corridor along y in [-1.5, 0.5] with an alcove x in [3, 5] up to y = 2 on its north
/// side, walls 0.15 m thick, the unknown beyond; a talker in the alcove at (4, 1.5) and
/// the robot's stops along y = -0.5 at x = 0, 1, ..., 9.
pub(in crate::mapper) fn alcove(config: IasmConfig) -> (Mapper, Vec<Pose>) {
    let mapper = ghost_mapper_on(
        |[x, y]| {
            let alcove = (3.0..5.0).contains(&x);
            match (x, y) {
                (_, y) if (-1.5..0.5).contains(&y) => Cell::Free,
                (_, y) if alcove && (0.5..2.0).contains(&y) => Cell::Free,
                (_, y) if (-1.65..-1.5).contains(&y) => Cell::Occupied,
                (x, y) if (2.85..5.15).contains(&x) && (0.5..2.15).contains(&y) => Cell::Occupied,
                (_, y) if (0.5..0.65).contains(&y) => Cell::Occupied,
                _ => Cell::Unknown,
            }
        },
        config,
    );
    let poses = (0..10).map(|i| Pose::new(i as f64, -0.5, 0.0)).collect();
    (mapper, poses)
}

pub(in crate::mapper) const TALKER: [f64; 2] = [4.0, 1.5];

/// The talker's reflections in the alcove's side walls (faces x = 3 and x = 5) that reach
/// stop `p`: the bearing to its image, where the path through the point of reflection
/// stays in the free space of the map.
fn reflections(mapper: &Mapper, p: &Pose) -> Vec<f64> {
    [(3.0, [2.0, TALKER[1]]), (5.0, [6.0, TALKER[1]])]
        .into_iter()
        .filter_map(|(face, image): (f64, [f64; 2])| {
            let t = (face - p.x) / (image[0] - p.x);
            let at = [face, p.y + t * (image[1] - p.y)];
            let clear = |a: [f64; 2], b: [f64; 2]| {
                // Stop short of the wall at both ends: the reflection point is on it.
                let (a, b) = (lerp(a, b, 0.03), lerp(a, b, 0.97));
                mapper.map.first_occupied(a, b).is_none()
            };
            ((0.0..1.0).contains(&t)
                && (0.7..1.95).contains(&at[1])
                && clear(p.position(), at)
                && clear(at, TALKER))
            .then(|| p.bearing_to(image))
        })
        .collect()
}

/// The ray of a DoA at `bearing` (world frame) heard at stop `k`.
fn ray(poses: &[Pose], k: usize, bearing: f64) -> Ray {
    Ray {
        stop: k,
        from: poses[k].position(),
        bearing,
        twin: None,
        shared: false,
    }
}

/// What the mapper's rules refuse of `sources`, each stop having heard `rows` (complete
/// but for the stops in `cut`, whose rows the SSL said it cut at N).
fn judge_rows(
    mapper: &Mapper,
    poses: &[Pose],
    rows: &[Vec<f64>],
    cut: &[usize],
    sources: &mut Vec<Source>,
) -> Vec<Refused> {
    let mut complete = mapper.complete_by_length(rows);
    let mut said_cut = vec![false; poses.len()];
    for &k in cut {
        (complete[k], said_cut[k]) = (false, true);
    }
    let stops = stops_with(poses, rows, &complete, &said_cut);
    let mut left = vec![Vec::new(); poses.len()];
    mapper.drop_implausible(sources, &stops, &mut left)
}

fn lerp(a: [f64; 2], b: [f64; 2], t: f64) -> [f64; 2] {
    [a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])]
}

/// What each stop hears: the talker first where the map leaves it in sight, then its
/// reflections.
fn heard(mapper: &Mapper, poses: &[Pose]) -> Vec<Vec<f64>> {
    poses
        .iter()
        .map(|p| {
            let direct = mapper.map.first_occupied(p.position(), TALKER).is_none();
            direct
                .then(|| p.bearing_to(TALKER))
                .into_iter()
                .chain(reflections(mapper, p))
                .collect()
        })
        .collect()
}

/// The sources a map would hold: the talker from the stops that see it, and a source
/// where the reflections cross, with the rays it would take (`off_deg` turns them).
fn talker_and_crossing(mapper: &Mapper, poses: &[Pose], heard: &[Vec<f64>]) -> Vec<Source> {
    let sees: Vec<usize> = (0..poses.len())
        .filter(|&k| {
            mapper
                .map
                .first_occupied(poses[k].position(), TALKER)
                .is_none()
        })
        .collect();
    let rays: Vec<Ray> = heard
        .iter()
        .enumerate()
        .flat_map(|(k, row)| {
            let skip = usize::from(sees.contains(&k));
            row.iter().skip(skip).map(move |&b| ray(poses, k, b))
        })
        .collect();
    let start = least_squares_crossing(&rays).expect("the reflections cross");
    let (at, _) = fit_bearings(start, &rays, 5f64.to_radians(), Trim::OFF).expect("a fit");
    let mut crossing = heard_from(at, poses, &[]);
    crossing.observations = rays.len();
    crossing.rays = rays;
    vec![heard_from(TALKER, poses, &sees), crossing]
}

fn judged(config: IasmConfig, silence_the_talker: bool) -> (Vec<Source>, Vec<Refused>, [f64; 2]) {
    let (mapper, poses) = alcove(config);
    let mut rows = heard(&mapper, &poses);
    let mut sources = talker_and_crossing(&mapper, &poses, &rows);
    let crossing = [sources[1].x, sources[1].y];
    if silence_the_talker {
        // The stops that see the talker report only the reflections they heard.
        for k in stops_of(&sources[0].rays) {
            rows[k].remove(0);
        }
    }
    let refused = judge_rows(&mapper, &poses, &rows, &[], &mut sources);
    (sources, refused, crossing)
}

#[test]
fn where_a_talkers_reflections_cross_there_is_no_source() {
    let (kept, refused, crossing) = judged(IasmConfig::default(), false);
    // The reflections from either side cross at the alcove's mouth, in the room, from
    // at least four stops (the scene is what the rule is for).
    let (mapper, poses) = alcove(IasmConfig::default());
    let reflected = heard(&mapper, &poses)
        .iter()
        .zip(&poses)
        .filter(|(row, p)| {
            row.len() > usize::from(mapper.map.first_occupied(p.position(), TALKER).is_none())
        })
        .count();
    assert!(reflected >= 4, "{reflected} stops hear a reflection");
    assert!(
        (3.0..5.0).contains(&crossing[0]) && (0.0..1.2).contains(&crossing[1]),
        "{crossing:?}"
    );
    // The talker stays; the crossing is refused as its reflections.
    assert_eq!(
        kept.iter().map(|s| [s.x, s.y]).collect::<Vec<_>>(),
        vec![TALKER]
    );
    assert_eq!(refused.len(), 1, "{refused:?}");
    assert_eq!(refused[0].rule, Refusal::Reflection);
    // Without the rule the crossing stands.
    let (kept, refused, _) = judged(
        IasmConfig {
            reflections: false,
            ..IasmConfig::default()
        },
        false,
    );
    assert!(refused.is_empty(), "{refused:?}");
    assert_eq!(kept.len(), 2);
}

#[test]
fn a_reflection_is_heard_with_its_direct_sound() {
    // The same rays, but the stops that see the talker did not hear it: what they heard
    // at its reflections' bearings is no reflection of it (a reflection is weaker than the
    // direct sound), so the crossing, heard from them too, is not explained away.
    let (kept, refused, _) = judged(IasmConfig::default(), true);
    assert!(
        refused.iter().all(|r| r.rule != Refusal::Reflection),
        "{refused:?}"
    );
    assert!(kept.len() == 2, "{kept:?}");
}

#[test]
fn a_talker_where_the_reflections_cross_stays() {
    // A second talker stands where the first's reflections cross, heard by the stops
    // that heard those reflections, beside what they heard before: its own rays fit it
    // exactly, and the first talker's images, all within the vote's gate of them, miss
    // most of them by more than a sigma (up to 7.6 degrees): it is a source, not the
    // first's reflections.
    let (mapper, poses) = alcove(IasmConfig::default());
    let mut rows = heard(&mapper, &poses);
    let sources = talker_and_crossing(&mapper, &poses, &rows);
    let second = [sources[1].x, sources[1].y];
    let heard_it = stops_of(&sources[1].rays);
    let sigma = 5f64.to_radians();
    let misses: Vec<f64> = sources[1].rays.iter().map(|r| r.miss(second)).collect();
    assert!(misses.iter().all(|&m| m < 2.0 * sigma), "{misses:?}");
    assert!(
        2 * misses.iter().filter(|&&m| m > sigma).count() > misses.len(),
        "{misses:?}"
    );
    for &k in &heard_it {
        rows[k].push(poses[k].bearing_to(second));
    }
    let mut sources = vec![sources[0].clone(), heard_from(second, &poses, &heard_it)];
    let refused = judge_rows(&mapper, &poses, &rows, &[], &mut sources);
    assert!(refused.is_empty(), "{refused:?}");
    assert_eq!(sources.len(), 2);
}

/// The bearing `share` of the way from the talker to its image in the alcove's west wall
/// (face x = 3, image at (2, 1.5)) from stop `p`: one peak of the direct sound and its
/// reflection, 1 m apart, as a small array hears them (half-way for a reflection as
/// strong as the direct sound, nearer the talker for a weaker one).
fn blend_of_west_image(p: &Pose, share: f64) -> f64 {
    let (direct, image) = (p.bearing_to(TALKER), p.bearing_to([2.0, TALKER[1]]));
    direct + share * wrap_rad(image - direct)
}

#[test]
fn a_peak_between_a_talker_and_its_reflection_is_no_source() {
    // The stops at x = 4, 5 and 6 see the talker and, 30-45 degrees beside it, its image
    // in the alcove's west wall 1 m away; each hears one peak half-way between them as
    // well as the talker (`corridor_alcoves`, MVDR). Those peaks meet near the west wall,
    // in the alcove: a source there is their blend, not a second talker.
    let (mapper, poses) = alcove(IasmConfig::default());
    let blended = [4, 5, 6];
    let mut rows: Vec<Vec<f64>> = poses.iter().map(|_| Vec::new()).collect();
    for k in 2..=6 {
        rows[k].push(poses[k].bearing_to(TALKER));
    }
    let rays: Vec<Ray> = blended
        .iter()
        .map(|&k| {
            let b = blend_of_west_image(&poses[k], 0.5);
            rows[k].push(b);
            ray(&poses, k, b)
        })
        .collect();
    let at = least_squares_crossing(&rays).expect("the peaks cross");
    assert!(
        (3.0..3.5).contains(&at[0]) && (1.2..1.8).contains(&at[1]),
        "{at:?}"
    );
    // Each peak misses the talker and its image by 9-23 degrees, more than a sigma: no
    // direct sound of it, and no reflection the first-order rule takes.
    let sigma = 5f64.to_radians();
    for r in &rays {
        let image = poses[r.stop].bearing_to([2.0, TALKER[1]]);
        assert!(r.miss(TALKER) > sigma, "stop {}", r.stop);
        assert!(wrap_rad(r.bearing - image).abs() > sigma, "stop {}", r.stop);
    }
    let judge = |config: IasmConfig| {
        let mapper = Mapper {
            config,
            ..mapper.clone()
        };
        let mut ghost = heard_from(at, &poses, &[]);
        ghost.observations = rays.len();
        ghost.rays = rays.clone();
        let mut sources = vec![heard_from(TALKER, &poses, &[2, 3, 4, 5, 6]), ghost];
        // The SSL cut the rows of stops 2 and 3 at N (the corridor's stops before an
        // alcove hear more peaks than N): their silence towards the blend says nothing,
        // and the rule that weighs silence (absence_ratio) is not what is judged here.
        let refused = judge_rows(&mapper, &poses, &rows, &[2, 3], &mut sources);
        (sources, refused)
    };
    let (kept, refused) = judge(IasmConfig::default());
    assert_eq!(
        kept.iter().map(|s| [s.x, s.y]).collect::<Vec<_>>(),
        vec![TALKER]
    );
    assert_eq!(refused.len(), 1, "{refused:?}");
    assert_eq!(refused[0].rule, Refusal::Reflection);
    // Without the rule the blend stands as a source.
    let (kept, refused) = judge(IasmConfig {
        reflections: false,
        ..IasmConfig::default()
    });
    assert!(refused.is_empty(), "{refused:?}");
    assert_eq!(kept.len(), 2);
}

#[test]
fn a_talker_behind_a_source_far_from_its_wall_is_no_blend_of_it() {
    // A second talker in the corridor, 1.7 m in front of the alcove's back wall (face
    // y = 2): from four of the five stops that see the alcove's talker, it lies between
    // that second talker and its image in the back wall, within 60 degrees and more than
    // a sigma from each, but the image's path is more than twice the direct one (2.2-3.4
    // times), too weak to blend with it. (In `corridor_alcoves` a ghost 1.8 m in front of
    // the second alcove's back wall explained that alcove's talker away so.)
    let (mapper, poses) = alcove(IasmConfig::default());
    let front = [4.0, 0.3];
    let image = [4.0, 3.7];
    let sees: Vec<usize> = (2..=6).collect();
    let sigma = 5f64.to_radians();
    let between: Vec<usize> = sees
        .iter()
        .copied()
        .filter(|&k| {
            let p = &poses[k];
            let (b, d, i) = (
                p.bearing_to(TALKER),
                p.bearing_to(front),
                p.bearing_to(image),
            );
            let far = |q: [f64; 2]| (q[0] - p.x).hypot(q[1] - p.y);
            wrap_rad(b - d).abs() > sigma
                && wrap_rad(b - i).abs() > sigma
                && wrap_rad(b - d).abs() + wrap_rad(b - i).abs() <= wrap_rad(i - d).abs() + 1e-9
                && wrap_rad(i - d).abs() <= 60f64.to_radians()
                && far(image) > 2.0 * far(front)
        })
        .collect();
    assert_eq!(between, vec![2, 3, 5, 6]);
    let rows: Vec<Vec<f64>> = poses
        .iter()
        .enumerate()
        .map(|(k, p)| {
            let mut row = vec![p.bearing_to(front)];
            if sees.contains(&k) {
                row.push(p.bearing_to(TALKER));
            }
            row
        })
        .collect();
    let all: Vec<usize> = (0..poses.len()).collect();
    let mut sources = vec![
        heard_from(front, &poses, &all),
        heard_from(TALKER, &poses, &sees),
    ];
    let refused = judge_rows(&mapper, &poses, &rows, &[], &mut sources);
    assert!(refused.is_empty(), "{refused:?}");
    assert_eq!(sources.len(), 2);
}

/// The alcove's talker heard directly from the stops `direct` and from the stops
/// `blended` as one peak `share` of the way to its image in the alcove's west wall: where
/// the bearing fit of all those rays (trimmed as the rounds trim it, every ray kept)
/// places it, and where [`Mapper::place_by_own_reflections`] then places it under
/// `config`, with the stops it takes as blends ([`fitted_and_placed`]).
fn unblended_talker(
    direct: &[usize],
    blended: &[usize],
    share: f64,
    config: IasmConfig,
) -> ([f64; 2], [f64; 2], Vec<usize>) {
    let (mapper, poses) = alcove(config);
    let sigma = 5f64.to_radians();
    let mut talker = heard_from(TALKER, &poses, direct);
    talker.rays.extend(
        blended
            .iter()
            .map(|&k| ray(&poses, k, blend_of_west_image(&poses[k], share))),
    );
    for r in &talker.rays[direct.len()..] {
        assert!(r.miss(TALKER) > sigma, "stop {}", r.stop);
    }
    let none = vec![Vec::new(); poses.len()];
    let (fit, s, _) = fitted_and_placed(&mapper, &poses, talker, TALKER, none);
    (fit, [s.x, s.y], s.blends)
}

/// Where the bearing fit of `source`'s rays from `start` places it (trimmed as the rounds
/// trim it; every ray kept), and the source as [`Mapper::place_by_own_reflections`] then
/// leaves it, the stops `poses` having heard its rays and the DoAs of `pool` (world
/// bearings by stop) that no source explains; and what `pool` holds after.
fn fitted_and_placed(
    mapper: &Mapper,
    poses: &[Pose],
    mut source: Source,
    start: [f64; 2],
    mut pool: Vec<Vec<f64>>,
) -> ([f64; 2], Source, Vec<Vec<f64>>) {
    let trim = Trim::of(&IasmConfig::default());
    let sigma = 5f64.to_radians();
    let (fit, kept) = fit_bearings(start, &source.rays, sigma, trim).expect("a fit");
    assert_eq!(kept.len(), source.rays.len(), "the gate keeps every ray");
    (source.x, source.y) = (fit[0], fit[1]);
    let mut heard = pool.clone();
    for r in &source.rays {
        heard[r.stop].push(r.bearing);
    }
    let n = poses.len();
    let stops = stops_with(poses, &heard, &vec![true; n], &vec![false; n]);
    let mut sources = vec![source];
    mapper.place_by_own_reflections(&mut sources, &stops, &mut pool);
    (fit, sources.remove(0), pool)
}

fn dist(a: [f64; 2], b: [f64; 2]) -> f64 {
    (a[0] - b[0]).hypot(a[1] - b[1])
}

#[test]
fn a_talker_heard_blended_with_its_image_stands_where_its_own_rays_meet() {
    // The alcove's talker, 1 m from the alcove's west wall, heard directly from four
    // stops (x = 2, 3, 4, 6) and from the stop at x = 5 as one peak half-way between it
    // and its image in that wall, 15 degrees beside it (`l_wing`'s wing talker, MVDR).
    // The bearing fit of all five, trimmed as the rounds trim it, is pulled 0.28 m towards
    // the wall: the blend, within the gate, bends it and misses it by too little to be
    // trimmed. Judged from where most rays meet, it is a blend, and the talker stands
    // where its own four rays meet.
    let (fit, at, blends) = unblended_talker(&[2, 3, 4, 6], &[5], 0.5, IasmConfig::default());
    let pulled = dist(fit, TALKER);
    assert!(pulled > 0.25, "{fit:?}");
    assert!(dist(at, TALKER) < 1e-6, "{at:?}, {pulled:.3} m off before");
    assert_eq!(blends, vec![5], "the blend is named (--explain says so)");
    // Without the rule the fit of all five stays.
    let off = IasmConfig {
        reflections: false,
        ..IasmConfig::default()
    };
    let (_, at, blends) = unblended_talker(&[2, 3, 4, 6], &[5], 0.5, off);
    assert_eq!((at, blends), (fit, vec![]));
}

#[test]
fn blends_are_judged_from_where_the_rays_meet_in_the_room() {
    // `l_wing` moved 4 m south: a hall x in [0, 8], y in [-4, -1], a wing x in [5, 8] up to
    // y = 3, walls 0.15 m thick, the unknown beyond. The wing's talker at (7.2, 2), 0.8 m
    // from its east wall, is heard by stops driving north along x = 6 (y = -2.2, -1.7,
    // ...): from the first three as one peak with its image in that wall, 8-9.5 degrees
    // towards it (MVDR at N = 4), and directly from the next four with the errors the
    // renderings show (+3, +0.6, -0.3, +0.3 degrees). The bearing fit of all seven stands
    // in the wing's corner, 1.3 m off. The three blends and the ray 3 degrees off meet
    // beyond that corner: there the rays' median miss is least, and from there no ray
    // lies between the talker and its image. From where they meet in the room, the blends
    // stand out and the talker stands where its own four rays meet: 0.2 m off, the
    // depth that four stops in a line towards it fix.
    let talker = [7.2, 2.0];
    let mapper = ghost_mapper_on(
        |[x, y]| {
            let hall = (0.0..8.0).contains(&x) && (-4.0..-1.0).contains(&y);
            let wing = (5.0..8.0).contains(&x) && (-1.0..3.0).contains(&y);
            let walls = (-0.15..8.15).contains(&x) && (-4.15..3.15).contains(&y);
            match () {
                _ if hall || wing => Cell::Free,
                _ if walls && (y < -0.85 || x > 4.85) => Cell::Occupied,
                _ => Cell::Unknown,
            }
        },
        IasmConfig::default(),
    );
    let poses: Vec<Pose> = (0..7)
        .map(|k| Pose::new(6.0, -2.2 + 0.5 * k as f64, std::f64::consts::FRAC_PI_2))
        .collect();
    let mut source = heard_from(talker, &poses, &[0, 1, 2, 3, 4, 5, 6]);
    // Towards the image is clockwise from these stops.
    let off = [-9.5f64, -8.0, -8.0, 3.0, 0.6, -0.3, 0.3];
    for (r, off) in source.rays.iter_mut().zip(off) {
        r.bearing += off.to_radians();
    }
    let (least, _) = crate::mapper::refine::Medians::of(source.rays.iter()).least(talker);
    assert!(
        least[0] > 8.15 && least[1] > 3.15,
        "beyond the corner: {least:?}"
    );
    let none = vec![Vec::new(); poses.len()];
    let (fit, placed, _) = fitted_and_placed(&mapper, &poses, source, talker, none);
    assert!(dist(fit, talker) > 1.0, "the blends pull the fit: {fit:?}");
    assert!(dist([placed.x, placed.y], talker) < 0.25, "{placed:?}");
    assert_eq!(placed.blends, vec![0, 1, 2]);
}

#[test]
fn a_ray_from_a_stop_the_map_hides_a_talker_from_is_its_image() {
    // The alcove's talker heard directly from the stops at x = 1..5, and from x = 7, where
    // the corridor's north wall hides it, at its image in the alcove's west wall (half a
    // degree off; 12 degrees beside the bearing to the talker): the reflection is what
    // reaches that stop (`corridor_alcoves`' first alcove talker, MVDR, from the stop past
    // the alcove's east corner). The bearing fit of all six is pulled towards it, and no
    // ray lies between the talker and its image. The stop cannot hear the talker's direct
    // sound, so its ray is taken as the image, left out of the fit, and named so.
    let (mapper, poses) = alcove(IasmConfig::default());
    let mut talker = heard_from(TALKER, &poses, &[1, 2, 3, 4, 5]);
    let image = poses[7].bearing_to([2.0, TALKER[1]]);
    talker
        .rays
        .push(ray(&poses, 7, image + 0.5f64.to_radians()));
    talker.observations = talker.rays.len();
    let none = vec![Vec::new(); poses.len()];
    let (fit, placed, _) = fitted_and_placed(&mapper, &poses, talker, TALKER, none);
    assert!(dist(fit, TALKER) > 0.1, "the image pulls the fit: {fit:?}");
    assert!(dist([placed.x, placed.y], TALKER) < 1e-6, "{placed:?}");
    assert_eq!((placed.images, placed.blends), (vec![7], vec![]));
}

#[test]
fn a_talker_stays_where_its_blends_explain_its_rays_no_better() {
    // Two peaks of five blend the talker with its image, 40 % of the way to it (18
    // degrees off from the stop at x = 4, where the image is 45 degrees beside the
    // talker; 7 from x = 6, 18 degrees beside): taken as peaks anywhere in so wide a
    // wedge, they explain the rays less well than the bearing fit of all five, 0.33 m
    // off, explains them within a sigma or two (the squared misses sum to 3.2 sigma^2,
    // the blends' share 3.4): the mapper does not know how far towards its image a
    // blend lies, and keeps the fit. Without that comparison it would move.
    let (fit, at, blends) = unblended_talker(&[2, 3, 5], &[4, 6], 0.4, IasmConfig::default());
    assert!(dist(fit, TALKER) > 0.3, "{fit:?}");
    assert_eq!((at, blends), (fit, vec![]));
}

/// A talker at `talker` in the alcove heard directly from the stops `direct` (each DoA
/// `off` radians beside it, alternately either side) and from the stops `imaged` at a
/// `share` of the way from its bearing to its image's in the alcove's back wall (face
/// y = 2); its rays' bearing fit, and where [`Mapper::place_by_own_reflections`] puts it
/// and the stops it names as images ([`fitted_and_placed`]).
fn unmirrored(
    talker: [f64; 2],
    direct: &[usize],
    imaged: &[usize],
    share: f64,
    off: f64,
) -> ([f64; 2], [f64; 2], Vec<usize>) {
    let (fit, s, _) = unmirrored_with_spare(talker, direct, imaged, &[], share, off);
    (fit, [s.x, s.y], s.images)
}

/// [`unmirrored`], with the stops `spare` having heard the talker's image too, at the same
/// share of the way, in DoAs that no source explains: the fit, the talker placed, and
/// what is left unexplained.
fn unmirrored_with_spare(
    talker: [f64; 2],
    direct: &[usize],
    imaged: &[usize],
    spare: &[usize],
    share: f64,
    off: f64,
) -> ([f64; 2], Source, Vec<Vec<f64>>) {
    let (mapper, poses) = alcove(IasmConfig::default());
    let image = [talker[0], 4.0 - talker[1]];
    let heard_at_image = |k: usize| {
        let (to, image) = (poses[k].bearing_to(talker), poses[k].bearing_to(image));
        to + share * wrap_rad(image - to)
    };
    let mut source = heard_from(talker, &poses, direct);
    for (i, r) in source.rays.iter_mut().enumerate() {
        r.bearing += if i % 2 == 0 { off } else { -off };
    }
    (source.rays).extend(imaged.iter().map(|&k| ray(&poses, k, heard_at_image(k))));
    let mut pool = vec![Vec::new(); poses.len()];
    for &k in spare {
        pool[k].push(heard_at_image(k));
    }
    fitted_and_placed(&mapper, &poses, source, talker, pool)
}

#[test]
fn a_talker_heard_by_its_image_stands_where_its_unfolded_rays_meet() {
    // The talker, 0.5 m from the alcove's back wall, heard directly from the stops at
    // x = 2, 4 and 6 (1.5 degrees off, alternately either side), and from x = 3 and 5,
    // which see its image in the back wall 8 degrees beside it, only by that image
    // (`corridor_alcoves`' second alcove: two coherent arrivals closer than the array's
    // main lobe make one peak, at either or beyond). The bearing fit of all five stands
    // 0.29 m towards the wall; the two rays unfolded in the wall pass the talker, and the
    // fit of all five so taken stands within the direct rays' error of it, the two stops
    // named (--explain says so).
    let (fit, at, images) = unmirrored(TALKER, &[2, 4, 6], &[3, 5], 1.0, 1.5f64.to_radians());
    let pulled = dist(fit, TALKER);
    assert!(pulled > 0.25, "{fit:?}");
    assert!(dist(at, TALKER) < 0.05, "{at:?}, {pulled:.3} m off before");
    assert!(images.contains(&3) && images.contains(&5), "{images:?}");
}

#[test]
fn a_doa_no_source_explains_that_passes_a_talkers_image_is_its_image() {
    // Stops every 0.5 m in front of the alcove (x = 2-6). The talker, 0.5 m from the
    // alcove's back wall, heard directly from x = 2, 3.5, 4.5 and 6 (1.5 degrees off,
    // alternately either side) and by its image from x = 2.5 only: one image ray is no
    // evidence of an image (it may be the noise), and the talker stays where its five rays
    // meet, 0.2 m or more towards the wall. The stop at x = 5.5 heard the image too, in a DoA the
    // rounds left to no source. Taken with the talker's rays, it passes the talker's image
    // as the ray from x = 2.5 does: both unfolded in the wall, the talker stands within the
    // direct rays' error of the truth, and the DoA is its own now.
    let (mapper, _) = alcove(IasmConfig::default());
    let poses: Vec<Pose> = (0..9)
        .map(|i| Pose::new(2.0 + 0.5 * f64::from(i), -0.5, 0.0))
        .collect();
    let image = [TALKER[0], 4.0 - TALKER[1]];
    let mut talker = heard_from(TALKER, &poses, &[0, 3, 5, 8]);
    for (i, r) in talker.rays.iter_mut().enumerate() {
        r.bearing += 1.5f64.to_radians() * if i % 2 == 0 { 1.0 } else { -1.0 };
    }
    talker
        .rays
        .insert(1, ray(&poses, 1, poses[1].bearing_to(image)));
    let place =
        |pool: Vec<Vec<f64>>| fitted_and_placed(&mapper, &poses, talker.clone(), TALKER, pool);
    let (fit, alone, _) = place(vec![Vec::new(); poses.len()]);
    assert!(dist(fit, TALKER) > 0.2, "{fit:?}");
    assert_eq!(([alone.x, alone.y], alone.images), (fit, vec![]));
    let mut pool = vec![Vec::new(); poses.len()];
    pool[7].push(poses[7].bearing_to(image));
    let (_, s, pool) = place(pool);
    assert!(
        dist([s.x, s.y], TALKER) < 0.05,
        "{:?} from {fit:?}",
        [s.x, s.y]
    );
    assert_eq!(s.images, vec![1, 7]);
    assert!(s.rays.iter().any(|r| r.stop == 7));
    assert_eq!(
        s.observations, 6,
        "the talker's five DoAs and the one it took"
    );
    assert!(pool.iter().all(Vec::is_empty), "{pool:?}");
}

#[test]
fn a_ray_between_a_talker_and_its_image_is_no_image() {
    // The same stops, the two peaks 55 % of the way to the image (4.4 degrees from the
    // talker, 3.6 from its image). Seen from where most rays meet, pulled towards the wall
    // as the fit is, they pass the source nearer than its image: no ray is taken as the
    // image, and the talker stays where the fit put it, 0.16 m towards the wall. A peak
    // part-way to the image is a blend of the two (`unblended`'s, where it lies more than a
    // sigma from both), not the image.
    let (fit, at, images) = unmirrored(TALKER, &[2, 4, 6], &[3, 5], 0.55, 1.5f64.to_radians());
    assert!(dist(fit, TALKER) > 0.1, "{fit:?}");
    assert_eq!((at, images), (fit, vec![]));
}
