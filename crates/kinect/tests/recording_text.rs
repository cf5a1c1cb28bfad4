//! The two text files of a recording folder, parsed in memory: `intrinsics.json`
//! ([`Intrinsics::from_json_str`], which [`Intrinsics::read`] calls) and `depth_times.txt`
//! ([`parse_depth_times`], which [`Recording::open`] calls). Property tests: what is written reads
//! back equal, arbitrary text gives `Ok` or a typed error, and every refused time names its line.

use proptest::prelude::*;
use symcorr_kinect::camera::{FOCAL_RANGE_PX, MAX_IMAGE_SIDE};
use symcorr_kinect::{
    parse_depth_times, Distortion, Intrinsics, KinectError, Mirroring, Recording,
};

// ---------------------------------------------------------------------------------------------
// intrinsics.json

/// A focal length [`Intrinsics::validate`] accepts: the ends of the range, any value in it, and
/// values spread over its decades.
fn focal() -> impl Strategy<Value = f64> {
    let (lo, hi) = (*FOCAL_RANGE_PX.start(), *FOCAL_RANGE_PX.end());
    prop_oneof![
        Just(lo),
        Just(hi),
        lo..=hi,
        (0.0..=5.0f64).prop_map(move |e| 10f64.powf(e).clamp(lo, hi)),
    ]
}

/// A principal point coordinate [`Intrinsics::validate`] accepts for an image side of `side` px:
/// in `-side/2 ..= 3·side/2`, its ends included.
fn principal(side: u32) -> impl Strategy<Value = f64> {
    let s = f64::from(side);
    prop_oneof![
        Just(-0.5 * s),
        Just(1.5 * s),
        Just(0.5 * s),
        (0.0..=1.0f64).prop_map(move |a| -0.5 * s + a * (2.0 * s)),
    ]
}

/// An image side [`Intrinsics::validate`] accepts.
fn side() -> impl Strategy<Value = u32> {
    prop_oneof![Just(1), Just(MAX_IMAGE_SIDE), 1..=MAX_IMAGE_SIDE]
}

/// Intrinsics that validate: a pinhole camera, or one with a lens model scaled to the image
/// ([`lens_for`]).
fn valid_intrinsics() -> impl Strategy<Value = Intrinsics> {
    (side(), side(), focal(), focal())
        .prop_flat_map(|(width, height, fx, fy)| {
            (principal(width), principal(height), mirroring()).prop_map(
                move |(cx, cy, mirroring)| Intrinsics {
                    width,
                    height,
                    fx,
                    fy,
                    cx,
                    cy,
                    mirroring,
                    distortion: None,
                },
            )
        })
        .prop_flat_map(|k| {
            prop_oneof![Just(None), lens_for(&k).prop_map(Some)]
                .prop_map(move |distortion| Intrinsics { distortion, ..k })
        })
        .prop_filter("the lens model describes the image", |k| {
            k.validate().is_ok()
        })
}

/// A lens model of the strength depth cameras have on an image whose farthest corner lies at
/// the normalised radius `c`: each radial term moves that corner by at most a tenth of its
/// radius, the tangential terms by at most a hundredth.
fn lens_for(k: &Intrinsics) -> impl Strategy<Value = Distortion> {
    let (w, h) = (f64::from(k.width), f64::from(k.height));
    let c = (k.cx.abs().max((w - k.cx).abs()) / k.fx)
        .hypot(k.cy.abs().max((h - k.cy).abs()) / k.fy)
        .max(1e-3);
    let term = move |power: i32| (-0.1..=0.1f64).prop_map(move |t| t / c.powi(power));
    (
        [term(2), term(4), term(6), term(2), term(4), term(6)],
        [(-0.01..=0.01f64), (-0.01..=0.01f64)],
    )
        .prop_map(move |(radial, [p1, p2])| Distortion {
            radial,
            tangential: [p1 / c, p2 / c],
        })
}

/// Any lens model, non-finite coefficients included.
fn any_lens() -> impl Strategy<Value = Option<Distortion>> {
    prop_oneof![
        Just(None),
        (
            [
                any_value(),
                any_value(),
                any_value(),
                any_value(),
                any_value(),
                any_value()
            ],
            [any_value(), any_value()]
        )
            .prop_map(|(radial, tangential)| Some(Distortion { radial, tangential })),
    ]
}

/// Either way round.
fn mirroring() -> impl Strategy<Value = Mirroring> {
    prop_oneof![Just(Mirroring::Mirrored), Just(Mirroring::Direct)]
}

/// Any `f64`, non-finite ones and values near the accepted ranges included.
fn any_value() -> impl Strategy<Value = f64> {
    prop_oneof![
        any::<f64>(),
        Just(f64::NAN),
        Just(f64::INFINITY),
        Just(f64::NEG_INFINITY),
        Just(0.0),
        Just(-0.0),
        -1e6..1e6f64,
    ]
}

/// Intrinsics that may or may not validate.
fn any_intrinsics() -> impl Strategy<Value = Intrinsics> {
    (
        prop_oneof![any::<u32>(), 0..=MAX_IMAGE_SIDE + 1],
        prop_oneof![any::<u32>(), 0..=MAX_IMAGE_SIDE + 1],
        any_value(),
        any_value(),
        any_value(),
        any_value(),
        mirroring(),
        any_lens(),
    )
        .prop_map(
            |(width, height, fx, fy, cx, cy, mirroring, distortion)| Intrinsics {
                width,
                height,
                fx,
                fy,
                cx,
                cy,
                mirroring,
                distortion,
            },
        )
}

/// The bits of every value, so that equality is exact (and -0.0 is not 0.0).
fn bits(k: &Intrinsics) -> (u32, u32, [u64; 4], Mirroring, Option<[u64; 8]>) {
    (
        k.width,
        k.height,
        [k.fx, k.fy, k.cx, k.cy].map(f64::to_bits),
        k.mirroring,
        k.distortion.map(|d| {
            let [k1, k2, k3, k4, k5, k6] = d.radial;
            [k1, k2, k3, k4, k5, k6, d.tangential[0], d.tangential[1]].map(f64::to_bits)
        }),
    )
}

/// Text that looks like an intrinsics file: its keys and an unknown one, numbers, format tags,
/// booleans, `null`, `[]`.
const INTRINSICS_LIKE: &str = concat!(
    "\\{ ?(\"(format|width|height|fx|fy|cx|cy|cz|mirrored|distortion)\" ?: ?",
    "(-?[0-9]{1,6}(\\.[0-9]{1,3})?(e-?[0-9]{1,3})?|\"symcorr\\.intrinsics/[0-9]\"|null|true|false|\\[\\]",
    "|\\[(-?0\\.[0-9]{1,3}(e-?[0-9])?, ?){3,7}-?0\\.[0-9]{1,3}\\])",
    " ?,?){0,9}\\}"
);

/// `Ok` intrinsics validate and round-trip; an error is `Json` naming the file.
fn check_intrinsics_result(
    result: Result<Intrinsics, KinectError>,
    file: &str,
) -> Result<(), TestCaseError> {
    match result {
        Ok(k) => {
            prop_assert!(k.validate().is_ok(), "accepted but invalid: {:?}", k);
            let back = Intrinsics::from_json_str(&k.to_json(), file);
            prop_assert_eq!(back.ok(), Some(k));
        }
        Err(KinectError::Json { file: f, message }) => {
            prop_assert_eq!(f, file);
            prop_assert!(!message.is_empty());
        }
        Err(e) => prop_assert!(false, "not a Json error: {e:?}"),
    }
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    #[test]
    fn valid_intrinsics_write_and_read_back_equal(k in valid_intrinsics()) {
        prop_assert!(k.validate().is_ok(), "{:?}", k);
        let json = k.to_json();
        let back = Intrinsics::from_json_str(&json, "<memory>").unwrap();
        prop_assert_eq!(bits(&back), bits(&k), "{}", json);
        // The serde path (`Intrinsics` is `Serialize`) writes the same text.
        prop_assert_eq!(serde_json::to_string(&k).unwrap(), json);
    }

    /// Reversing the columns: pixel `u` of one camera and `width − 1 − u` of the other see
    /// one ray (to rounding), projection agrees, and the direction flips.
    #[test]
    fn reversed_columns_see_the_same_rays(
        k in valid_intrinsics(),
        (fu, fv, z) in (0.0..1.0f64, 0.0..1.0f64, 0.5..8.0f64),
    ) {
        let r = k.columns_reversed();
        prop_assert_ne!(r.mirroring, k.mirroring);
        prop_assert_eq!(r.columns_reversed().mirroring, k.mirroring);
        let w = f64::from(k.width);
        let (u, v) = (fu * (w - 1.0), fv * (f64::from(k.height) - 1.0));
        let (p, q) = (k.unproject(u, v, z), r.unproject(w - 1.0 - u, v, z));
        // Lengths scale with the pixel offsets and the depth over the focal length.
        let scale = z * (w + (k.cx - u).abs()) / k.fx.min(k.fy);
        prop_assert!((p - q).norm() <= 1e-12 * scale.max(1.0), "{:?} {:?}", p, q);
        let ([pu, pv], [qu, qv]) = (k.project(&p), r.project(&p));
        prop_assert!((pu + qu - (w - 1.0)).abs() <= 1e-9 * (w + k.cx.abs()), "{} {}", pu, qu);
        prop_assert!((pv - qv).abs() == 0.0);
    }

    #[test]
    fn the_reader_accepts_exactly_what_validates(k in any_intrinsics()) {
        let json = k.to_json();
        match (k.validate(), Intrinsics::from_json_str(&json, "k.json")) {
            (Ok(()), Ok(back)) => prop_assert_eq!(bits(&back), bits(&k)),
            (Err(_), Err(KinectError::Json { file, .. })) => prop_assert_eq!(file, "k.json"),
            (valid, read) => {
                prop_assert!(false, "validate {:?} but read {:?} ({})", valid, read, json)
            }
        }
    }

    #[test]
    fn arbitrary_text_is_no_intrinsics_panic(text in any::<String>()) {
        check_intrinsics_result(Intrinsics::from_json_str(&text, "<memory>"), "<memory>")?;
    }

    #[test]
    fn intrinsics_like_text_gives_ok_or_a_json_error(text in INTRINSICS_LIKE) {
        check_intrinsics_result(Intrinsics::from_json_str(&text, "k.json"), "k.json")?;
    }

    #[test]
    fn damaged_intrinsics_give_ok_or_a_json_error(
        k in valid_intrinsics(),
        at in any::<prop::sample::Index>(),
        with in prop_oneof![Just(""), Just("}"), Just("\""), Just("-"), Just("9"), Just(",")],
    ) {
        let mut json = k.to_json();
        let i = at.index(json.len());
        json.replace_range(i..=i, with);
        check_intrinsics_result(Intrinsics::from_json_str(&json, "k.json"), "k.json")?;
    }
}

#[test]
fn read_parses_the_file_with_from_json_str() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("intrinsics.json");
    let file = p.display().to_string();
    let k = Intrinsics {
        width: 8,
        height: 6,
        fx: 7.0,
        fy: 7.5,
        cx: -4.0,
        cy: 9.0,
        mirroring: symcorr_kinect::Mirroring::Mirrored,
        distortion: None,
    };
    k.write(&p).unwrap();
    assert_eq!(std::fs::read_to_string(&p).unwrap(), k.to_json());
    assert_eq!(Intrinsics::read(&p).unwrap(), k);
    for text in [
        "",
        "{",
        r#"{"format":"symcorr.intrinsics/2","width":8,"height":6,"fx":7,"fy":7,"cx":3,"cy":2}"#,
        r#"{"format":"symcorr.intrinsics/1","width":8,"height":6,"fx":7,"fy":7,"cx":3}"#,
        r#"{"format":"symcorr.intrinsics/1","width":0,"height":6,"fx":7,"fy":7,"cx":3,"cy":2}"#,
        r#"{"format":"symcorr.intrinsics/1","width":8,"height":6,"fx":7,"fy":7,"cx":13,"cy":2}"#,
    ] {
        std::fs::write(&p, text).unwrap();
        let from_file = Intrinsics::read(&p).unwrap_err().to_string();
        let from_text = Intrinsics::from_json_str(text, &file).unwrap_err();
        assert!(matches!(from_text, KinectError::Json { .. }), "{from_text}");
        assert_eq!(from_file, from_text.to_string());
        assert!(from_file.starts_with(&format!("{file}: ")), "{from_file}");
    }
    // Not UTF-8: a Json error naming the file and the byte, not an I/O error.
    std::fs::write(&p, b"{\"format\xff\":1}").unwrap();
    let e = Intrinsics::read(&p).unwrap_err();
    assert!(matches!(e, KinectError::Json { .. }), "{e}");
    assert_eq!(e.to_string(), format!("{file}: not UTF-8 text (byte 8)"));
}

// ---------------------------------------------------------------------------------------------
// depth_times.txt

/// Finite times, strictly increasing, 0 to 40 of them, from anywhere in the `f64` range or near
/// a recording's (seconds, a few per 30 Hz frame).
fn increasing_times() -> impl Strategy<Value = Vec<f64>> {
    let anywhere =
        prop::collection::vec(any::<f64>().prop_filter("finite", |t| t.is_finite()), 0..40)
            .prop_map(|mut v| {
                v.sort_by(f64::total_cmp);
                v.dedup_by(|b, a| b <= a);
                v
            });
    let recording =
        (-1e4..1e4f64, prop::collection::vec(1e-9..1.0f64, 0..40)).prop_map(|(start, steps)| {
            let mut v = vec![start];
            for s in steps {
                let next = v[v.len() - 1] + s;
                if next > v[v.len() - 1] {
                    v.push(next);
                }
            }
            v
        });
    prop_oneof![anywhere, recording]
}

/// How the lines of a times file are ended and padded.
#[derive(Debug, Clone, Copy)]
struct Layout {
    crlf: bool,
    final_newline: bool,
    pad: bool,
}

fn layout() -> impl Strategy<Value = Layout> {
    (any::<bool>(), any::<bool>(), any::<bool>()).prop_map(|(crlf, final_newline, pad)| Layout {
        crlf,
        final_newline,
        pad,
    })
}

/// The lines as a times file.
fn times_file(lines: &[String], layout: Layout) -> String {
    let end = if layout.crlf { "\r\n" } else { "\n" };
    let mut text = lines
        .iter()
        .map(|l| {
            if layout.pad && !l.trim().is_empty() {
                format!(" \t{l}  ")
            } else {
                l.clone()
            }
        })
        .collect::<Vec<_>>()
        .join(end);
    if layout.final_newline && !lines.is_empty() {
        text.push_str(end);
    }
    text
}

/// Each time with `{}` (which reads back to the same `f64`).
fn lines_of(times: &[f64]) -> Vec<String> {
    times.iter().map(|t| format!("{t}")).collect()
}

/// The times file of `times` with the line `at` picks replaced by `word`, parsed, and that
/// line's number (1-based).
fn with_line_replaced(
    times: &[f64],
    at: prop::sample::Index,
    word: &str,
    layout: Layout,
) -> (Result<Vec<f64>, KinectError>, usize) {
    let k = at.index(times.len());
    let mut lines = lines_of(times);
    lines[k] = word.to_string();
    let text = times_file(&lines, layout);
    (
        parse_depth_times(&text, lines.len(), "depth_times.txt"),
        k + 1,
    )
}

/// The error must be `Parse` naming `file` and `line`, with `what` in its message.
fn assert_parse_error(
    result: Result<Vec<f64>, KinectError>,
    line: usize,
    what: &str,
) -> Result<(), TestCaseError> {
    match result {
        Err(KinectError::Parse {
            file,
            line: l,
            message,
        }) => {
            prop_assert_eq!(file, "depth_times.txt");
            prop_assert_eq!(l, line, "{}", message);
            prop_assert!(message.contains(what), "{message:?} lacks {what:?}");
        }
        other => prop_assert!(
            false,
            "expected a Parse error at line {line}, got {other:?}"
        ),
    }
    Ok(())
}

/// Strings that look like a times file: numbers, signs, exponents, `inf`/`NaN`, blanks, lines.
const TIMES_LIKE: &str =
    "([-+]?[0-9]{0,4}(\\.[0-9]{0,4})?(e[-+]?[0-9]{1,3})?|inf|NaN|x|)[ \t]?(\r?\n)?";

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    #[test]
    fn increasing_times_read_back_exactly(times in increasing_times(), layout in layout()) {
        let text = times_file(&lines_of(&times), layout);
        let back = parse_depth_times(&text, times.len(), "depth_times.txt").unwrap();
        prop_assert_eq!(
            back.iter().map(|t| t.to_bits()).collect::<Vec<_>>(),
            times.iter().map(|t| t.to_bits()).collect::<Vec<_>>(),
            "{:?}", text
        );
    }

    #[test]
    fn a_wrong_number_of_times_is_refused(
        times in increasing_times(),
        frames in 0usize..50,
        layout in layout(),
    ) {
        prop_assume!(frames != times.len());
        let text = times_file(&lines_of(&times), layout);
        let e = parse_depth_times(&text, frames, "depth_times.txt").unwrap_err();
        prop_assert!(matches!(e, KinectError::Recording { .. }), "{}", e);
        let noun = |n: usize, one: &str| format!("{n} {one}{}", if n == 1 { "" } else { "s" });
        prop_assert_eq!(
            e.to_string(),
            format!(
                "depth_times.txt: {} for {} (one line per frame)",
                noun(times.len(), "time"),
                noun(frames, "depth frame")
            )
        );
    }

    #[test]
    fn a_time_not_after_the_previous_names_its_line(
        times in increasing_times().prop_filter("two times", |v| v.len() >= 2),
        at in any::<prop::sample::Index>(),
        earlier in any::<prop::sample::Index>(),
        layout in layout(),
    ) {
        let k = 1 + at.index(times.len() - 1);
        let mut bad = times.clone();
        bad[k] = times[earlier.index(k)]; // equal to or before the time of line k
        let text = times_file(&lines_of(&bad), layout);
        let result = parse_depth_times(&text, bad.len(), "depth_times.txt");
        assert_parse_error(result, k + 1, "(times must increase strictly)")?;
    }

    #[test]
    fn a_time_that_is_not_finite_names_its_line(
        times in increasing_times().prop_filter("a time", |v| !v.is_empty()),
        at in any::<prop::sample::Index>(),
        word in prop::sample::select(
            &["NaN", "nan", "inf", "-inf", "+infinity", "Infinity", "1e309", "-1e400"][..]
        ),
        layout in layout(),
    ) {
        let (result, line) = with_line_replaced(&times, at, word, layout);
        assert_parse_error(result, line, "is not finite")?;
    }

    #[test]
    fn an_empty_line_names_its_line(
        times in increasing_times(),
        at in any::<prop::sample::Index>(),
        blank in prop::sample::select(&["", " ", "\t", " \t "][..]),
        layout in layout(),
    ) {
        prop_assume!(!times.is_empty());
        let mut lines = lines_of(&times);
        // Before some time: blank lines after the last one are no frames (the next test).
        let k = at.index(lines.len());
        lines.insert(k, blank.to_string());
        let text = times_file(&lines, layout);
        let result = parse_depth_times(&text, lines.len(), "depth_times.txt");
        assert_parse_error(result, k + 1, "empty line; expected the time of depth frame")?;
    }

    #[test]
    fn blank_lines_after_the_last_time_are_ignored(
        times in increasing_times(),
        blanks in prop::collection::vec(prop::sample::select(&["", " ", "\t", "\r"][..]), 1..4),
        layout in layout(),
    ) {
        let mut lines = lines_of(&times);
        lines.extend(blanks.iter().map(|b| b.to_string()));
        let text = times_file(&lines, layout);
        let back = parse_depth_times(&text, times.len(), "depth_times.txt").unwrap();
        prop_assert_eq!(back, times, "{:?}", text);
    }

    #[test]
    fn a_line_that_is_not_a_number_names_its_line(
        times in increasing_times().prop_filter("a time", |v| !v.is_empty()),
        at in any::<prop::sample::Index>(),
        word in prop::sample::select(&["abc", "1,5", "0x10", "1 2", "--1", "1e", ".", "0.1s"][..]),
        layout in layout(),
    ) {
        let (result, line) = with_line_replaced(&times, at, word, layout);
        assert_parse_error(result, line, &format!("`{word}` is not a number"))?;
    }

    #[test]
    fn arbitrary_text_gives_times_or_a_typed_error(
        text in prop_oneof![
            any::<String>(),
            prop::collection::vec(TIMES_LIKE, 0..12).prop_map(|v| v.concat()),
        ],
        frames in prop_oneof![0usize..12, Just(usize::MAX)],
    ) {
        match parse_depth_times(&text, frames, "depth_times.txt") {
            Ok(times) => {
                prop_assert_eq!(times.len(), frames);
                prop_assert!(times.iter().all(|t| t.is_finite()), "{:?}", times);
                prop_assert!(times.windows(2).all(|w| w[0] < w[1]), "{:?}", times);
            }
            Err(KinectError::Parse { file, line, .. }) => {
                prop_assert_eq!(file, "depth_times.txt");
                prop_assert!((1..=text.lines().count()).contains(&line), "line {}", line);
            }
            Err(KinectError::Recording { file, message }) => {
                prop_assert_eq!(file, "depth_times.txt");
                let frames = if frames == 1 { "1 depth frame".to_string() } else { format!("{frames} depth frames") };
                let end = format!("for {frames} (one line per frame)");
                prop_assert!(message.ends_with(&end), "{}", message);
            }
            Err(e) => prop_assert!(false, "unexpected error kind: {:?}", e),
        }
    }
}

#[test]
fn recording_open_reports_the_parsers_errors_on_its_times_file() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    Intrinsics {
        width: 2,
        height: 2,
        fx: 2.0,
        fy: 2.0,
        cx: 1.0,
        cy: 1.0,
        mirroring: symcorr_kinect::Mirroring::Mirrored,
        distortion: None,
    }
    .write(dir.join("intrinsics.json"))
    .unwrap();
    std::fs::create_dir(dir.join("depth")).unwrap();
    let frame = symcorr_kinect::DepthFrame::new(2, 2, vec![1000; 4]).unwrap();
    for i in 0..3 {
        let png = dir.join(format!("depth/{i:06}.png"));
        symcorr_kinect::write_depth_png16(png, &frame).unwrap();
    }
    let times = dir.join("depth_times.txt");
    let file = times.display().to_string();
    for text in [
        "0\n0.1\n0.2\n",
        "0\n0.1\n",
        "0\n\n0.2\n",
        "0\nNaN\n0.2\n",
        "1\n0.5\n2\n",
    ] {
        std::fs::write(&times, text).unwrap();
        let parsed = parse_depth_times(text, 3, &file).map_err(|e| e.to_string());
        let opened = Recording::open(dir)
            .map(|r| r.times().to_vec())
            .map_err(|e| e.to_string());
        assert_eq!(opened, parsed, "{text:?}");
    }
    // Not UTF-8: refused before parsing, naming the byte.
    std::fs::write(&times, b"0\n0.\xff1\n0.2\n").unwrap();
    let e = Recording::open(dir).unwrap_err();
    assert!(matches!(e, KinectError::Recording { .. }), "{e}");
    assert_eq!(e.to_string(), format!("{file}: not UTF-8 text (byte 4)"));
}

/// A long line that is not a number, with control characters in it, is quoted briefly and
/// escaped: the message stays one short line whatever the file holds.
#[test]
fn a_long_line_that_is_not_a_number_is_quoted_briefly() {
    let line = format!("x\u{1b}[2J{}", "y".repeat(1 << 20));
    let e = parse_depth_times(&format!("0\n{line}\n"), 2, "depth_times.txt").unwrap_err();
    let message = e.to_string();
    assert!(matches!(e, KinectError::Parse { line: 2, .. }), "{message}");
    assert!(message.len() < 200, "{} bytes", message.len());
    assert!(
        !message.contains('\u{1b}') && message.contains("\\u{1b}"),
        "{message}"
    );
    assert!(message.contains('…'), "{message}");
}

/// A byte-order mark before either file, as Windows tools write UTF-8, is skipped: the same
/// intrinsics and times as without it.
#[test]
fn a_byte_order_mark_is_skipped() {
    let k = Intrinsics::kinect_v1();
    let with_bom = format!("\u{feff}{}", k.to_json());
    assert_eq!(Intrinsics::from_json_str(&with_bom, "k.json").unwrap(), k);
    let times = parse_depth_times("\u{feff}0.5\n0.6\n", 2, "depth_times.txt").unwrap();
    assert_eq!(times, vec![0.5, 0.6]);
    // Only one mark, and only at the start.
    assert!(parse_depth_times("0.5\n\u{feff}0.6\n", 2, "depth_times.txt").is_err());
}
