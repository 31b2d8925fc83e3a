//! The binaries, as a user runs them: results on success, a clear message
//! and a non-zero exit on bad input.

use std::process::Command;

fn track(args: &[&str]) -> (bool, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_track")).args(args).output().unwrap();
    (out.status.success(), String::from_utf8_lossy(&out.stdout).into(), String::from_utf8_lossy(&out.stderr).into())
}

fn fixture(name: &str) -> String {
    format!("{}/../fixtures/{name}.pft", env!("CARGO_MANIFEST_DIR"))
}

#[test]
fn tracks_a_fixture_and_writes_its_track() {
    let dir = std::env::temp_dir().join(format!("pftrack-cli-{}", std::process::id()));
    let (ok, stdout, stderr) = track(&["fixture", &fixture("gray_smooth"), "--out-dir", dir.to_str().unwrap()]);
    assert!(ok, "{stderr}");
    assert!(stdout.contains("gray_smooth"), "{stdout}");
    let text = std::fs::read_to_string(dir.join("gray_smooth.txt")).unwrap();
    // Reason: one line per frame (30 frames), the first the initial box.
    assert_eq!(text.lines().count(), 30);
    let first: Vec<f32> = text.lines().next().unwrap().split(',').map(|v| v.parse().unwrap()).collect();
    let truth =
        host_tests::fixture::Fixture::load(std::path::Path::new(&fixture("gray_smooth"))).unwrap().frames[0].truth;
    assert!((first[0] - truth.x).abs() < 0.01 && (first[3] - truth.height).abs() < 0.01);
    std::fs::remove_dir_all(dir).ok();
}

#[test]
fn bad_inputs_fail_clearly() {
    let dir = std::env::temp_dir().join(format!("pftrack-cli-bad-{}", std::process::id()));
    std::fs::create_dir_all(dir.join("seq/img")).unwrap();
    let out = dir.to_str().unwrap().to_string();

    let (ok, _, err) = track(&["otb", "/no/such/sequence", "--out-dir", &out]);
    assert!(!ok && err.contains("no such file or folder"), "{err}");

    // A sequence with ground truth but no frames.
    std::fs::write(dir.join("seq/groundtruth.txt"), "1,2,3,4\n").unwrap();
    let (ok, _, err) = track(&["otb", dir.join("seq").to_str().unwrap(), "--out-dir", &out]);
    assert!(!ok && err.contains("no JPEG or PNG frames"), "{err}");

    // A frame that is not an image.
    std::fs::write(dir.join("seq/img/0001.jpg"), b"not a jpeg").unwrap();
    let (ok, _, err) = track(&["otb", dir.join("seq").to_str().unwrap(), "--out-dir", &out]);
    assert!(!ok && err.contains("0001.jpg"), "{err}");

    // A truncated fixture.
    let bytes = std::fs::read(fixture("gray_smooth")).unwrap();
    let cut = dir.join("cut.pft");
    std::fs::write(&cut, &bytes[..bytes.len() / 2]).unwrap();
    let (ok, _, err) = track(&["fixture", cut.to_str().unwrap(), "--out-dir", &out]);
    assert!(!ok && err.contains("file ends inside frame"), "{err}");

    // A bad setting.
    let (ok, _, err) = track(&["fixture", &fixture("gray_smooth"), "--set", "alpha=7", "--out-dir", &out]);
    assert!(!ok && err.contains("alpha"), "{err}");
    std::fs::remove_dir_all(dir).ok();
}

#[test]
fn score_breaks_the_overlap_down_into_size_and_centre() {
    // Reason: by hand, three frames of a 10x10 target at the origin: one
    // exact box (IoU 1, above 20 of the 21 thresholds), one at the right
    // centre twice the size (IoU 1/4, above 5: 0 to 0.2), one of the right
    // size 30 px off (IoU 0, above none). AUC (20 + 5 + 0) / 63 = 0.397;
    // with the truth's size the second becomes exact, (20 + 20 + 0) / 63 =
    // 0.635; at the truth's centre the third does, (20 + 5 + 20) / 63 =
    // 0.714.
    let dir = std::env::temp_dir().join(format!("pftrack-cli-score-{}", std::process::id()));
    std::fs::create_dir_all(dir.join("seq")).unwrap();
    std::fs::create_dir_all(dir.join("res")).unwrap();
    std::fs::write(dir.join("seq/groundtruth.txt"), "0,0,10,10\n0,0,10,10\n0,0,10,10\n").unwrap();
    std::fs::write(dir.join("res/seq.txt"), "0,0,10,10\n-5,-5,20,20\n30,0,10,10\n").unwrap();
    let results = format!("mine={}", dir.join("res").display());
    let plots = dir.join("plots");
    let (ok, stdout, stderr) = track(&[
        "score",
        "--truth",
        dir.join("seq").to_str().unwrap(),
        "--results",
        &results,
        "--plots",
        plots.to_str().unwrap(),
    ]);
    assert!(ok, "{stderr}");
    assert!(stdout.contains("| mine | 0.397 | 0.635 (+0.238) | 0.714 (+0.317) |"), "{stdout}");
    std::fs::remove_dir_all(dir).ok();
}

#[test]
fn score_pairs_runs_and_reports_their_spread() {
    // Reason: by hand, a 10x10 target at the origin over two frames (AUC
    // counts both, as above: an exact box is above 20 of the 21
    // thresholds, one twice the size, IoU 1/4, above 5). Set `a`: run 1
    // exact twice, AUC 40/42 = 0.95238; run 2 exact then twice the size,
    // 25/42 = 0.59524. Their standard deviation: 0.35714 / sqrt 2 =
    // 0.2525. Set `b`: exact in both runs, sd 0; paired with `a`, the
    // differences 0 and 0.35714, their mean 0.1786 and its standard error
    // (sd 0.2525) / sqrt 2 = 0.1786. Set `c` has one run: no spread, no
    // row.
    let dir = std::env::temp_dir().join(format!("pftrack-cli-runs-{}", std::process::id()));
    for d in ["seq", "a1", "a2", "b1", "b2"] {
        std::fs::create_dir_all(dir.join(d)).unwrap();
    }
    std::fs::write(dir.join("seq/groundtruth.txt"), "0,0,10,10\n".repeat(2)).unwrap();
    for d in ["a1", "b1", "b2"] {
        std::fs::write(dir.join(d).join("seq.txt"), "0,0,10,10\n0,0,10,10\n").unwrap();
    }
    std::fs::write(dir.join("a2/seq.txt"), "0,0,10,10\n-5,-5,20,20\n").unwrap();
    let set = |name: &str, runs: &[&str]| {
        let folders: Vec<String> = runs.iter().map(|r| dir.join(r).display().to_string()).collect();
        format!("{name}={}", folders.join(","))
    };
    let (a, b, c) = (set("a", &["a1", "a2"]), set("b", &["b1", "b2"]), set("c", &["b1"]));
    let (seq, plots) = (dir.join("seq"), dir.join("plots"));
    let (ok, stdout, stderr) = track(&[
        "score",
        "--truth",
        seq.to_str().unwrap(),
        "--plots",
        plots.to_str().unwrap(),
        "--results",
        &a,
        &b,
        &c,
    ]);
    assert!(ok, "{stderr}");
    assert!(stdout.contains("| a | 2 | 0.2525 | - |"), "{stdout}");
    assert!(stdout.contains("| b | 2 | 0.0000 | +0.1786 ± 0.1786 |"), "{stdout}");
    assert!(!stdout.contains("| c | 1 |"), "{stdout}");
    // One run each: nothing to tell apart, no table.
    let (ok, stdout, stderr) =
        track(&["score", "--truth", seq.to_str().unwrap(), "--plots", plots.to_str().unwrap(), "--results", &c]);
    assert!(ok && !stdout.contains("Between runs"), "{stderr}{stdout}");
    std::fs::remove_dir_all(dir).ok();
}

#[test]
fn score_tabulates_each_sequence_and_its_spread_between_runs() {
    // Reason: by hand, as above: a 10x10 target at the origin over two
    // frames; an exact box is above 20 of the 21 thresholds, one twice the
    // size (IoU 1/4) above 5. Sequence `near`: set `a` exact in run 1
    // (40/42) and twice the size in run 2's second frame (25/42): mean
    // 65/84 = 0.774, spread 15/42 = 0.357; set `c` (run 1 alone) 0.952,
    // no spread. Sequence `far`: both runs exact, 0.952 (0.000). The split
    // file puts `near` in tune and `far` in check.
    let dir = std::env::temp_dir().join(format!("pftrack-cli-per-sequence-{}", std::process::id()));
    for d in ["near", "far", "a1", "a2"] {
        std::fs::create_dir_all(dir.join(d)).unwrap();
    }
    for seq in ["near", "far"] {
        std::fs::write(dir.join(seq).join("groundtruth.txt"), "0,0,10,10\n".repeat(2)).unwrap();
        std::fs::write(dir.join("a1").join(format!("{seq}.txt")), "0,0,10,10\n0,0,10,10\n").unwrap();
    }
    std::fs::write(dir.join("a2/near.txt"), "0,0,10,10\n-5,-5,20,20\n").unwrap();
    std::fs::write(dir.join("a2/far.txt"), "0,0,10,10\n0,0,10,10\n").unwrap();
    std::fs::write(dir.join("split.txt"), "tune: near\ncheck: far\n").unwrap();
    let a = format!("a={},{}", dir.join("a1").display(), dir.join("a2").display());
    let c = format!("c={}", dir.join("a1").display());
    let (near, far, split, plots) = (dir.join("near"), dir.join("far"), dir.join("split.txt"), dir.join("plots"));
    let args = [
        "score",
        "--truth",
        near.to_str().unwrap(),
        far.to_str().unwrap(),
        "--plots",
        plots.to_str().unwrap(),
        "--split",
        split.to_str().unwrap(),
        "--results",
        &a,
        &c,
    ];
    let (ok, stdout, stderr) = track(&[&args[..], &["--per-sequence"]].concat());
    assert!(ok, "{stderr}");
    assert!(stdout.contains("| sequence | split | a | c |"), "{stdout}");
    assert!(stdout.contains("| near | tune | 0.774 (0.357) | 0.952 |"), "{stdout}");
    assert!(stdout.contains("| far | check | 0.952 (0.000) | 0.952 |"), "{stdout}");
    // Without the flag, no such table.
    let (ok, stdout, stderr) = track(&args);
    assert!(ok && !stdout.contains("Per sequence"), "{stderr}{stdout}");
    std::fs::remove_dir_all(dir).ok();
}

#[test]
fn score_ranks_missing_frames_by_each_trackers_confidence() {
    // Reason: by hand, a 10x10 target at the origin over five frames. The
    // first box is given, not tracked: it is left out though it misses.
    // Then an exact box, a disjoint one, one 5 px off (IoU 1/3) and a
    // disjoint one: 2 of 4 frames miss (IoU < 0.1), 50.0%. Confidences
    // 0.9, 0.2, 0.5, 0.6: of the four (not missing, missing) pairs, (0.9,
    // 0.2), (0.9, 0.6) and (0.5, 0.2) are ranked right, ROC AUC 0.750. A
    // folder without confidences has no ROC.
    let dir = std::env::temp_dir().join(format!("pftrack-cli-confidence-{}", std::process::id()));
    for d in ["seq", "with", "without"] {
        std::fs::create_dir_all(dir.join(d)).unwrap();
    }
    std::fs::write(dir.join("seq/groundtruth.txt"), "0,0,10,10\n".repeat(5)).unwrap();
    let boxes = "50,50,10,10\n0,0,10,10\n50,50,10,10\n5,0,10,10\n50,50,10,10\n";
    std::fs::write(dir.join("with/seq.txt"), boxes).unwrap();
    std::fs::write(dir.join("with/seq.confidence"), "0.9\n0.2\n0.5\n0.6\n").unwrap();
    std::fs::write(dir.join("without/seq.txt"), boxes).unwrap();
    let with = format!("with={}", dir.join("with").display());
    let without = format!("without={}", dir.join("without").display());
    let (seq, plots) = (dir.join("seq"), dir.join("plots"));
    let args = |results: &[&str]| {
        let mut a = vec!["score", "--truth", seq.to_str().unwrap(), "--plots", plots.to_str().unwrap(), "--results"];
        a.extend_from_slice(results);
        track(&a)
    };
    let (ok, stdout, stderr) = args(&[&with, &without]);
    assert!(ok, "{stderr}");
    assert!(stdout.contains("| 50.0% | 0.750 | - |"), "{stdout}");
    assert!(stdout.contains("| 50.0% | - | - |"), "{stdout}");
    // One confidence short: an error naming the file, not a shifted ranking.
    std::fs::write(dir.join("with/seq.confidence"), "0.9\n0.2\n0.5\n").unwrap();
    let (ok, _, stderr) = args(&[&with]);
    assert!(!ok && stderr.contains("seq.confidence") && stderr.contains("3 confidences for 5 frames"), "{stderr}");
    std::fs::remove_dir_all(dir).ok();
}

#[test]
fn an_otb_folder_of_several_targets_is_tracked_as_a_group_and_each_alone() {
    // Reason: the folder holds the frames of fixtures/groups/crossing.pft
    // as RGB888 in lossless PNGs and its two truths (as decimal floats that
    // parse back to the same values), so `otb` on it must track exactly as
    // `fixture` on the same frames in an RGB888 fixture: the same tracks
    // byte for byte. The group keeps both identities on that scene
    // (tests/groups.rs: no swap over 16 seeds), so 0 swaps on 0 of its 48
    // frames.
    use host_tests::fixture::Fixture;
    let dir = std::env::temp_dir().join(format!("pftrack-cli-otb-group-{}", std::process::id()));
    let seq = dir.join("crossing");
    let path = format!("{}/../fixtures/groups/crossing.pft", env!("CARGO_MANIFEST_DIR"));
    let mut fx = Fixture::load(std::path::Path::new(&path)).unwrap();
    let rgb: Vec<Vec<u8>> = (0..fx.frames.len()).map(|i| host_tests::scene::to_rgb(&fx.frame(i).unwrap())).collect();
    for (f, px) in fx.frames.iter_mut().zip(rgb) {
        f.pixels = px;
    }
    (fx.format, fx.stride) = (pftrack::PixelFormat::Rgb888, fx.width * 3);
    std::fs::create_dir_all(seq.join("img")).unwrap();
    let path = dir.join("crossing.pft");
    std::fs::write(&path, fx.to_bytes()).unwrap();
    let path = path.to_str().unwrap();
    let mut truths = vec![String::new(); 2];
    for (i, f) in fx.frames.iter().enumerate() {
        let img = image::RgbImage::from_raw(fx.width as u32, fx.height as u32, f.pixels.clone()).unwrap();
        img.save(seq.join(format!("img/{:05}.png", i + 1))).unwrap();
        for (k, m) in f.targets().enumerate() {
            // OTB's mark of an absent target: a zero size.
            let t = if m.visible_permille == 0 { pftrack::BoundingBox::default() } else { m.truth };
            truths[k] += &format!("{},{},{},{}\n", t.x, t.y, t.width, t.height);
        }
    }
    for (k, t) in truths.iter().enumerate() {
        std::fs::write(seq.join(format!("groundtruth.{}.txt", k + 1)), t).unwrap();
    }
    let (otb, direct, alone) = (dir.join("otb"), dir.join("direct"), dir.join("alone"));
    let (ok, stdout, stderr) = track(&["otb", seq.to_str().unwrap(), "--out-dir", otb.to_str().unwrap()]);
    assert!(ok, "{stderr}");
    for k in 1..=2 {
        assert!(stdout.lines().any(|l| l.starts_with(&format!("crossing#{k} ")) && l.contains(" 48 ")), "{stdout}");
    }
    assert!(stdout.contains("crossing: 0 identity swaps, on 0 of 48 frames (0.0%)"), "{stdout}");
    let (ok, _, stderr) = track(&["fixture", path, "--out-dir", direct.to_str().unwrap()]);
    assert!(ok, "{stderr}");
    for k in 1..=2 {
        for ext in ["txt", "confidence"] {
            let file = format!("crossing.{k}.{ext}");
            let text = std::fs::read_to_string(otb.join(&file)).unwrap();
            assert_eq!(text, std::fs::read_to_string(direct.join(&file)).unwrap(), "{file}");
            // A box for every frame; a confidence for every frame after the first.
            assert_eq!(text.lines().count(), if ext == "txt" { 48 } else { 47 }, "{file}");
        }
    }
    // `score` finds each target's track by the number of its truth.
    let results = format!("group={}", otb.display());
    let plots = dir.join("plots");
    let (ok, stdout, stderr) =
        track(&["score", "--truth", seq.to_str().unwrap(), "--results", &results, "--plots", plots.to_str().unwrap()]);
    assert!(ok && stdout.contains("2 sequences: crossing.1, crossing.2"), "{stdout}{stderr}");
    // Each target alone: rows and outputs of the same names, swaps counted.
    let (ok, stdout, stderr) = track(&["otb", seq.to_str().unwrap(), "--alone", "--out-dir", alone.to_str().unwrap()]);
    assert!(ok, "{stderr}");
    assert!(stdout.contains("crossing#1 ") && stdout.contains("crossing#2 "), "{stdout}");
    assert!(stdout.contains("crossing: ") && stdout.contains(" identity swaps, on "), "{stdout}");
    assert_eq!(std::fs::read_to_string(alone.join("crossing.2.txt")).unwrap().lines().count(), 48);
    // A group is of particle filters; alone, any tracker runs.
    let out = dir.join("other").to_str().unwrap().to_string();
    let (ok, _, stderr) = track(&["otb", seq.to_str().unwrap(), "--tracker", "meanshift", "--out-dir", &out]);
    assert!(!ok && stderr.contains("needs the particle filter"), "{stderr}");
    let (ok, _, stderr) =
        track(&["otb", seq.to_str().unwrap(), "--tracker", "meanshift", "--alone", "--out-dir", &out]);
    assert!(ok, "{stderr}");
    // A truth one box short is named.
    let short: String = truths[1].lines().skip(1).map(|l| format!("{l}\n")).collect();
    std::fs::write(seq.join("groundtruth.2.txt"), short).unwrap();
    let (ok, _, stderr) = track(&["otb", seq.to_str().unwrap(), "--out-dir", &out]);
    assert!(!ok && stderr.contains("48 frames in img/ but 47 ground-truth boxes (groundtruth.2.txt)"), "{stderr}");
    // The help says how such a folder is laid out and what --alone does.
    let (ok, help, _) = track(&["otb", "--help"]);
    assert!(ok && help.contains("groundtruth.1.txt") && help.contains("--alone"), "{help}");
    std::fs::remove_dir_all(dir).ok();
}
