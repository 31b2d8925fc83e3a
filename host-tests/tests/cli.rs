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
