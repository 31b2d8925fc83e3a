//! Frame views from arbitrary dimensions, stride, format and buffer: either a
//! typed error, or a view whose every pixel can be read.
#![no_main]
use libfuzzer_sys::fuzz_target;
use pftrack::{Frame, PixelFormat};

fuzz_target!(|input: (u16, u16, u32, u8, &[u8])| {
    let (w, h, stride, code, buf) = input;
    let Some(format) = PixelFormat::from_code(u16::from(code % 7)) else { return };
    let Ok(f) = Frame::new(buf, w as usize, h as usize, stride as usize, format) else { return };
    // A valid view: every corner and the centre read back a colour.
    for (x, y) in [
        (0, 0),
        (f.width() - 1, 0),
        (0, f.height() - 1),
        (f.width() - 1, f.height() - 1),
        (f.width() / 2, f.height() / 2),
    ] {
        assert!(f.rgb(x, y).is_some(), "({x}, {y}) of a valid {}x{} {:?} frame", f.width(), f.height(), f.format());
        assert!(f.row(y).is_some());
    }
    assert!(f.rgb(f.width(), 0).is_none() && f.row(f.height()).is_none());
});
