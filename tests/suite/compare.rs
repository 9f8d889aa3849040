//! `caustics compare` (docs/REPORTS.md) on ball_lens at 64²: every file it
//! promises is written and nothing else is left behind; the numbers in
//! report.json are the ones the tests' own code path
//! (`caustics::compare::metrics`, which tests/common uses) gives on the
//! images it wrote; the reference comes back from the cache; a technique
//! against its own image scores zero; a technique that does not apply is
//! skipped with its reason; bad arguments are one line and exit code 1.

use caustics::compare::metrics;
use caustics::compare::report::{CompareReport, TechniqueResult};
use caustics::output::read_exr;
use caustics::reference::Component;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

const SIZE: &str = "64";

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("caustics-compare-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn caustics(args: &[&str], cache: &Path) -> Output {
    Command::new(env!("CARGO_BIN_EXE_caustics"))
        .env(
            "VK_DRIVER_FILES",
            std::env::var_os("VK_DRIVER_FILES")
                .unwrap_or_else(|| "/usr/share/vulkan/icd.d/lvp_icd.x86_64.json".into()),
        )
        .env("CAUSTICS_CACHE_DIR", cache)
        .args(args)
        .output()
        .unwrap()
}

fn ok(out: &Output) -> String {
    let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
    assert!(
        out.status.success(),
        "{stdout}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    stdout
}

fn report(dir: &Path) -> CompareReport {
    serde_json::from_str(&std::fs::read_to_string(dir.join("report.json")).unwrap()).unwrap()
}

#[test]
fn compare_writes_every_file_with_the_tests_numbers() {
    let root = temp_dir("full");
    let (out, cache) = (root.join("out"), root.join("cache"));
    let scene = concat!(env!("CARGO_MANIFEST_DIR"), "/assets/scenes/ball_lens.toml");
    let base = [
        "compare", "--scene", scene, "--width", SIZE, "--height", SIZE, "--frames", "1",
    ];
    let mut args = base.to_vec();
    args.extend([
        "--photons",
        "524288",
        "--techniques",
        "direct,image_space,pinhole,water_photons",
        "--out",
        out.to_str().unwrap(),
    ]);
    let stdout = ok(&caustics(&args, &cache));
    assert!(stdout.contains("water_photons    skipped: "), "{stdout}");
    let r = report(&out);
    assert_eq!(r.run.schema, "caustics-report/1");
    assert_eq!((r.run.width, r.run.height), (64, 64));
    assert_eq!(r.reference.source, "traced");
    assert_eq!(r.reference.photons, 524288);
    let noise = r.reference.noise.expect("two half-runs give the noise");
    assert!(noise.flip > 0.0 && noise.flip < 0.5, "{noise:?}");
    assert_eq!(r.skipped.len(), 1);
    assert!(r.skipped[0].reason.contains("water"), "{:?}", r.skipped);

    // Every promised file, and nothing else (no staging folder).
    let mut expected = vec![
        "report.json".to_string(),
        "report.md".into(),
        "contact_sheet.png".into(),
        "reference_noise_flip.png".into(),
    ];
    for stem in [
        "reference",
        "reference_direct",
        "reference_surface_caustics",
        "reference_airlight",
        "reference_volume_caustics",
        "reference_other",
        "reference_emitted",
    ] {
        expected.push(format!("{stem}.exr"));
        expected.push(format!("{stem}.png"));
    }
    let names: Vec<&str> = r.techniques.iter().map(|t| t.technique.as_str()).collect();
    assert_eq!(names, ["direct", "image_space", "pinhole"]);
    for t in &r.techniques {
        let n = &t.technique;
        expected.extend([
            format!("{n}.exr"),
            format!("{n}.png"),
            format!("{n}_flip.png"),
        ]);
        for c in &t.components {
            let c = &c.component;
            expected.extend([
                format!("{n}_{c}.exr"),
                format!("{n}_{c}.png"),
                format!("{n}_{c}_flip.png"),
            ]);
        }
        // Rendered and written, not scored: no FLIP map (a component the
        // technique does not render has no image).
        let renders = caustics::techniques::find(n).unwrap().components;
        for c in &t.not_applicable {
            if renders.contains(&Component::parse(&c.component).unwrap()) {
                let c = &c.component;
                expected.extend([format!("{n}_{c}.exr"), format!("{n}_{c}.png")]);
            }
        }
        assert!(t.timing.frame_ms > 0.0 && !t.timing.passes_ms.is_empty());
    }
    // pinhole renders reflection caustics only: the glass ball's are not
    // its to score (issue 28).
    let pinhole = r
        .techniques
        .iter()
        .find(|t| t.technique == "pinhole")
        .unwrap();
    assert!(
        pinhole
            .components
            .iter()
            .all(|c| c.component != "surface_caustics"),
        "{:?}",
        pinhole.components
    );
    let not_scored = |t: &TechniqueResult| -> Vec<String> {
        t.not_applicable
            .iter()
            .map(|n| n.component.clone())
            .collect()
    };
    assert_eq!(not_scored(pinhole), ["surface_caustics"]);
    let reason = &pinhole.not_applicable[0].reason;
    assert!(
        reason.contains("reflection caustics only") && reason.contains("`lens`"),
        "{reason}"
    );
    let image_space_na = &r.techniques[1].not_applicable;
    assert!(image_space_na.is_empty(), "{image_space_na:?}");
    assert!(r.techniques[1].modelled.is_none(), "every component scored");
    // `direct` renders no caustics, and the reference has them.
    let direct = &r.techniques[0];
    assert_eq!(not_scored(direct), ["surface_caustics"]);
    assert!(direct.not_applicable[0].reason.contains("does not render"));
    let mut found: Vec<String> = std::fs::read_dir(&out)
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .collect();
    found.sort();
    expected.sort();
    assert_eq!(found, expected);

    // report.json holds what the tests' metrics give on the written images.
    let exr = |name: &str| read_exr(&out.join(format!("{name}.exr"))).unwrap().2;
    let image_space = r
        .techniques
        .iter()
        .find(|t| t.technique == "image_space")
        .unwrap();
    let caustics_result = image_space
        .components
        .iter()
        .find(|c| c.component == "surface_caustics")
        .expect("image_space renders surface caustics");
    let (m, _) = metrics::compare(
        &exr("image_space_surface_caustics"),
        &exr("reference_surface_caustics"),
        64,
        64,
        r.exposure,
    );
    assert_eq!(m, caustics_result.metrics);
    let (m, _) = metrics::compare(&exr("image_space"), &exr("reference"), 64, 64, r.exposure);
    assert_eq!(m, image_space.full);
    // pinhole's modelled components: its frame less its surface caustics
    // against the sum of the reference's other components (rgb; alpha as
    // the whole reference's).
    let less = |a: Vec<f32>, b: Vec<f32>| -> Vec<f32> {
        a.iter()
            .zip(&b)
            .enumerate()
            .map(|(i, (x, y))| if i % 4 == 3 { *x } else { x - y })
            .collect()
    };
    let mut scored = exr("reference");
    for (i, v) in scored.iter_mut().enumerate() {
        if i % 4 != 3 {
            *v = 0.0;
        }
    }
    for c in ["direct", "airlight", "volume_caustics", "other", "emitted"] {
        for (i, (t, v)) in scored
            .iter_mut()
            .zip(exr(&format!("reference_{c}")))
            .enumerate()
        {
            if i % 4 != 3 {
                *t += v;
            }
        }
    }
    let (m, _) = metrics::compare(
        &less(exr("pinhole"), exr("pinhole_surface_caustics")),
        &scored,
        64,
        64,
        r.exposure,
    );
    assert_eq!(Some(m), pinhole.modelled);
    let md = std::fs::read_to_string(out.join("report.md")).unwrap();
    assert!(
        md.contains(&format!("{:.4}", image_space.full.flip)),
        "{md}"
    );
    assert!(
        md.contains("| pinhole | surface_caustics | not applicable: pinhole renders reflection caustics only"),
        "{md}"
    );
    assert!(md.contains("| pinhole | modelled components |"), "{md}");

    // The same reference again comes from the cache, bit for bit.
    let again = root.join("again");
    let mut args = base.to_vec();
    args.extend([
        "--photons",
        "524288",
        "--techniques",
        "direct",
        "--out",
        again.to_str().unwrap(),
    ]);
    let stdout = ok(&caustics(&args, &cache));
    assert!(stdout.contains("reference from the cache"), "{stdout}");
    assert_eq!(report(&again).reference.source, "cache");
    assert_eq!(
        read_exr(&again.join("reference.exr")).unwrap().2,
        exr("reference")
    );

    // A technique against its own image: FLIP 0, energy 0.
    let own = root.join("own");
    let direct_exr = out.join("direct.exr");
    let mut args = base.to_vec();
    args.extend([
        "--reference",
        direct_exr.to_str().unwrap(),
        "--techniques",
        "direct",
        "--out",
        own.to_str().unwrap(),
    ]);
    ok(&caustics(&args, &cache));
    let r = report(&own);
    assert_eq!(r.reference.source, "file");
    let d = &r.techniques[0];
    assert_eq!(
        (d.full.flip, d.full.energy, d.full.rmse),
        (0.0, Some(0.0), 0.0)
    );
    assert!(d.components.is_empty(), "a file has no components");
    std::fs::remove_dir_all(&root).unwrap();
}

#[test]
fn bad_arguments_are_one_line_and_create_nothing() {
    let root = temp_dir("bad");
    let out = root.join("out");
    let scene = concat!(env!("CARGO_MANIFEST_DIR"), "/assets/scenes/ball_lens.toml");
    let small = root.join("small.exr");
    caustics::output::write_exr(&small, 8, 8, &[0.5; 8 * 8 * 4]).unwrap();
    let cases: [(&[&str], &str); 3] = [
        (&["--techniques", "no_such"], "unknown technique `no_such`"),
        (
            &["--reference", small.to_str().unwrap()],
            "is 8x8, the comparison 64x64",
        ),
        (
            &["--photons", "0"],
            "--photons 0: must be between 1 and 1e15",
        ),
    ];
    for (extra, needle) in cases {
        let mut args = vec![
            "compare",
            "--scene",
            scene,
            "--width",
            SIZE,
            "--height",
            SIZE,
            "--out",
            out.to_str().unwrap(),
        ];
        args.extend_from_slice(extra);
        let o = caustics(&args, &root);
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{stderr}");
        assert!(stderr.contains(needle), "{stderr}");
        assert_eq!(stderr.trim().lines().count(), 1, "{stderr}");
        assert!(!out.exists(), "{extra:?} left {}", out.display());
    }
    std::fs::remove_dir_all(&root).unwrap();
}
