//! The std harness around the `pftrack` core: the recorded-frame fixture
//! format, a deterministic scene generator, OTB sequence loading, the OTB
//! metrics, and a runner. The binaries `track` and `gen-fixtures` are thin
//! front ends to these.

pub mod fixture;
pub mod metrics;
pub mod otb;
pub mod picture;
pub mod plot;
pub mod runner;
pub mod scene;
pub mod settings;
