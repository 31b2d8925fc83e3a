//! What `track run` writes for each frame: a JSON line or a CSV row, and
//! the frame with the estimate drawn on it as YUV4MPEG2 video.

use crate::picture::{Canvas, annotate};
use pftrack::frame::rgb_to_yuv;
use pftrack::{BoundingBox, Estimate, Event, Frame, TrackState};
use std::io::Write;

/// One frame's outcome: frame 1 is the initial box.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Record {
    /// The frame, counted from 1.
    pub frame: usize,
    /// The tracker's state after the frame.
    pub state: TrackState,
    /// What happened in the frame, if anything.
    pub event: Option<Event>,
    /// The estimate's confidence in `[0, 1]`.
    pub confidence: f32,
    /// The estimated box (for frame 1, the box given).
    pub bbox: BoundingBox,
    /// The target's identity when several are tracked.
    pub target: Option<u16>,
}

impl Record {
    /// Frame 1: the tracker initialised on `bbox`.
    pub fn initial(bbox: BoundingBox) -> Self {
        Record {
            frame: 1,
            state: TrackState::Tracking,
            event: Some(Event::Initialised),
            confidence: 1.0,
            bbox,
            target: None,
        }
    }

    /// Frame `frame`'s estimate.
    pub fn of(frame: usize, e: &Estimate) -> Self {
        Record { frame, state: e.state, event: e.event, confidence: e.confidence, bbox: e.bbox(), target: None }
    }

    /// The record of target `id` of several.
    pub fn of_target(self, id: u16) -> Self {
        Record { target: Some(id), ..self }
    }

    /// The JSON line, without its newline: `{"frame":1,"state":"tracking",
    /// "event":"initialised","confidence":1.0,"box":[x,y,w,h]}`, with
    /// `"target":ID` after the frame when several targets are tracked.
    /// Numbers are written exactly (the shortest decimal that reads back as
    /// the same `f32`).
    pub fn json(&self) -> String {
        let event = self.event.map_or_else(|| "null".to_string(), |e| format!("\"{}\"", event_name(e)));
        let target = self.target.map_or_else(String::new, |id| format!("\"target\":{id},"));
        let [confidence, x, y, w, h] = self.numbers();
        format!(
            "{{\"frame\":{},{target}\"state\":\"{}\",\"event\":{event},\"confidence\":{confidence},\"box\":[{x},{y},{w},{h}]}}",
            self.frame,
            state_name(self.state),
        )
    }

    /// The CSV header that goes with [`Record::csv`] for one target.
    pub const CSV_HEADER: &'static str = "frame,state,confidence,x,y,w,h";

    /// The CSV header that goes with [`Record::csv`] for several targets.
    pub const CSV_HEADER_TARGETS: &'static str = "frame,target,state,confidence,x,y,w,h";

    /// The CSV row, without its newline (with the target's identity after
    /// the frame when several are tracked).
    pub fn csv(&self) -> String {
        let [confidence, x, y, w, h] = self.numbers();
        let target = self.target.map_or_else(String::new, |id| format!("{id},"));
        format!("{},{target}{},{confidence},{x},{y},{w},{h}", self.frame, state_name(self.state))
    }

    /// The confidence and the box as the records write them.
    fn numbers(&self) -> [String; 5] {
        let b = self.bbox;
        [self.confidence, b.x, b.y, b.width, b.height].map(number)
    }
}

/// A JSON number: the shortest decimal that reads back as `v`, or `null`
/// for the NaN or infinity JSON cannot say (the core never reports one).
fn number(v: f32) -> String {
    if v.is_finite() { format!("{v:?}") } else { "null".to_string() }
}

/// The state's name in the records.
pub fn state_name(s: TrackState) -> &'static str {
    match s {
        TrackState::Searching => "searching",
        TrackState::Tracking => "tracking",
        TrackState::Lost => "lost",
    }
}

/// The event's name in the records.
pub fn event_name(e: Event) -> &'static str {
    match e {
        Event::Initialised => "initialised",
        Event::Acquired => "acquired",
        Event::LostTarget => "lost",
        Event::Reacquired => "reacquired",
    }
}

/// Writes frames, with or without the estimate drawn on them, as a
/// YUV4MPEG2 stream:
/// 4:2:0 (`C420jpeg`, what `ffmpeg -i - out.mp4` encodes without a
/// conversion) for even sizes, 4:4:4 for odd ones, full range as the core
/// reads YUV.
pub struct Y4mWriter<W: Write> {
    encoder: y4m::Encoder<W>,
    size: (usize, usize),
    planes: [Vec<u8>; 3],
}

impl<W: Write> Y4mWriter<W> {
    /// Writes the stream's header: `width`x`height` at `rate` (frames per
    /// second as numerator and denominator).
    pub fn new(out: W, (width, height): (usize, usize), rate: (usize, usize)) -> Result<Self, String> {
        let c420 = width % 2 == 0 && height % 2 == 0;
        let colorspace = if c420 { y4m::Colorspace::C420jpeg } else { y4m::Colorspace::C444 };
        let range = y4m::VendorExtensionString::new(b"COLORRANGE=FULL".to_vec()).map_err(|e| e.to_string())?;
        let encoder = y4m::encode(width, height, y4m::Ratio::new(rate.0, rate.1))
            .with_colorspace(colorspace)
            .append_vendor_extension(range)
            .write_header(out)
            .map_err(|e| e.to_string())?;
        Ok(Y4mWriter { encoder, size: (width, height), planes: Default::default() })
    }

    /// Writes `frame`, with the estimate `est` (its ellipse and a status
    /// bar as long as its confidence, coloured by state) and `particles`
    /// drawn on it if given.
    pub fn write(&mut self, frame: &Frame<'_>, est: Option<&Estimate>, particles: &[(f32, f32)]) -> Result<(), String> {
        self.write_drawn(frame, |c| annotate(c, est, None, particles))
    }

    /// Writes `frame` with what `draw` draws on it.
    pub fn write_drawn(&mut self, frame: &Frame<'_>, draw: impl FnOnce(&mut Canvas)) -> Result<(), String> {
        let (w, h) = self.size;
        let mut c = Canvas::new(w, h, crate::scene::to_rgb(frame));
        draw(&mut c);
        let yuv: Vec<[u8; 3]> = c.pixels().as_chunks::<3>().0.iter().map(|&p| rgb_to_yuv(p)).collect();
        let [y, u, v] = &mut self.planes;
        y.clear();
        y.extend(yuv.iter().map(|p| p[0]));
        u.clear();
        v.clear();
        if w % 2 == 0 && h % 2 == 0 {
            // Each chroma sample is the rounded mean of its 2x2 block's.
            for by in 0..h / 2 {
                for bx in 0..w / 2 {
                    let at =
                        |dx: usize, dy: usize| yuv.get((2 * by + dy) * w + 2 * bx + dx).copied().unwrap_or_default();
                    let px = [at(0, 0), at(1, 0), at(0, 1), at(1, 1)];
                    let mean = |c: usize| ((px.iter().map(|p| p[c] as u16).sum::<u16>() + 2) / 4) as u8;
                    u.push(mean(1));
                    v.push(mean(2));
                }
            }
        } else {
            u.extend(yuv.iter().map(|p| p[1]));
            v.extend(yuv.iter().map(|p| p[2]));
        }
        let f = y4m::Frame::new([y.as_slice(), u.as_slice(), v.as_slice()], None);
        self.encoder.write_frame(&f).map_err(|e| e.to_string())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn records_read_as_the_contract_says() {
        // Reason: the exact line the command's contract shows for frame 1.
        let r = Record::initial(BoundingBox::new(120.0, 80.0, 40.0, 60.0));
        assert_eq!(
            r.json(),
            r#"{"frame":1,"state":"tracking","event":"initialised","confidence":1.0,"box":[120.0,80.0,40.0,60.0]}"#
        );
        assert_eq!(r.csv(), "1,tracking,1.0,120.0,80.0,40.0,60.0");
        let r = Record { frame: 7, state: TrackState::Lost, event: None, confidence: 0.25, ..r };
        assert!(r.json().contains(r#""state":"lost","event":null,"confidence":0.25"#), "{}", r.json());
        let r = Record { confidence: f32::NAN, ..r };
        assert!(r.json().contains(r#""confidence":null"#));
        let r = Record { confidence: 0.5, ..r }.of_target(3);
        assert!(r.json().starts_with(r#"{"frame":7,"target":3,"state":"lost""#), "{}", r.json());
        assert_eq!(r.csv(), "7,3,lost,0.5,120.0,80.0,40.0,60.0");
        assert_eq!(Record::CSV_HEADER_TARGETS.split(',').count(), r.csv().split(',').count());
    }
}
