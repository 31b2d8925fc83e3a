//! `track starts`: the changed first boxes of `ablate --sre`.

use host_tests::otb;

/// Prints the twelve starts of OTB's spatial robustness evaluation, one
/// `DX,DY,SCALE` per line, as `--perturb` takes them.
pub(crate) fn command() {
    for p in otb::SRE_STARTS {
        println!("{p}");
    }
}
