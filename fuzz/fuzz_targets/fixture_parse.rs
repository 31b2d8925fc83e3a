//! Any bytes as a fixture file, streamed the way the firmware reads it:
//! header, then records. Must never panic; a parsed header must describe
//! records whose metadata either parses or is refused with an error.
#![no_main]
use libfuzzer_sys::fuzz_target;
use pftrack_fixture::{HEADER_LEN, Header, RECORD_META_LEN, RecordMeta};

fuzz_target!(|data: &[u8]| {
    let Ok(h) = Header::parse(data) else { return };
    assert_eq!(Header::parse(&h.to_bytes()), Ok(h), "header round trip");
    let mut at = HEADER_LEN;
    for i in 0..h.frames {
        let Some(rec) = data.get(at..at.saturating_add(h.record_len())) else { break };
        for meta in rec.get(..h.meta_len()).unwrap_or_default().chunks(RECORD_META_LEN) {
            if let Ok(m) = RecordMeta::parse(meta, i) {
                assert!(m.truth.x.is_finite() && m.visible_permille <= 1000);
                assert_eq!(RecordMeta::parse(&m.to_bytes(), i), Ok(m), "record round trip");
            }
        }
        let _ = rec.get(h.meta_len()..);
        at += h.record_len();
    }
});
