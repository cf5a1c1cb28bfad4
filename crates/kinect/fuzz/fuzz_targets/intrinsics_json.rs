#![no_main]
//! `symcorr.intrinsics/1` reader (`Intrinsics::from_json_str`, which `Intrinsics::read` calls) on
//! arbitrary bytes decoded as lossy UTF-8: never panics, every error is a `KinectError::Json`
//! naming the file; accepted intrinsics validate, written (`to_json`) read back equal, and
//! every corner pixel, the middle pixel of every side and the principal point (when inside the
//! image) unproject to a finite point that projects back onto its pixel — with a lens model,
//! what validation promises for the border's pixels.
use libfuzzer_sys::fuzz_target;
use symcorr_kinect::{Intrinsics, KinectError};

fuzz_target!(|data: &[u8]| {
    let text = String::from_utf8_lossy(data);
    match Intrinsics::from_json_str(&text, "fuzz") {
        Err(KinectError::Json { file, .. }) => assert_eq!(file, "fuzz"),
        Err(e) => panic!("not a Json error: {e:?}"),
        Ok(k) => {
            assert!(k.validate().is_ok(), "accepted but invalid: {k:?}");
            let json = k.to_json();
            let back = Intrinsics::from_json_str(&json, "fuzz").expect("writer output parses");
            assert_eq!(back, k, "JSON round trip changed the intrinsics: {json}");
            assert_eq!(back.to_json(), json);
            let (w, h) = (f64::from(k.width) - 1.0, f64::from(k.height) - 1.0);
            let mut pixels = vec![(0.0, 0.0), (w, 0.0), (0.0, h), (w, h)];
            let (mu, mv) = ((w / 2.0).floor(), (h / 2.0).floor());
            pixels.extend([(mu, 0.0), (mu, h), (0.0, mv), (w, mv)]);
            if (0.0..=w).contains(&k.cx) && (0.0..=h).contains(&k.cy) {
                pixels.push((k.cx, k.cy));
            }
            for (u, v) in pixels {
                let p = k.unproject(u, v, 1.0);
                assert!(p.iter().all(|c| c.is_finite()), "{json}: ({u}, {v}) → {p:?}");
                let [pu, pv] = k.project(&p);
                let tolerance = 1e-6 * (1.0 + u.abs() + v.abs());
                assert!(
                    (pu - u).abs() <= tolerance && (pv - v).abs() <= tolerance,
                    "{json}: ({u}, {v}) → {p:?} → ({pu}, {pv})"
                );
            }
        }
    }
});
