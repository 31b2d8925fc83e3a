//! The std harness around the `pftrack` core: the recorded-frame fixture
//! format, a deterministic scene generator, frame sources (image folders,
//! Y4M and raw streams, fixtures), OTB sequences, the OTB metrics, and a
//! runner. The binaries `track` and `gen-fixtures` are thin
//! front ends to these.

pub mod fixture;
pub mod metrics;
pub mod otb;
pub mod picture;
pub mod plot;
pub mod record;
pub mod runner;
pub mod scene;
pub mod settings;
pub mod source;
