//! pftrack from Python: OpenCV's tracker interface (`init`, `update`) over
//! NumPy frames, with the core's determinism and errors.

use numpy::{PyReadonlyArray2, PyReadonlyArray3, PyUntypedArrayMethods};
use pftrack::{
    BoundingBox, Config, CorrelationCue, Error, Event, Frame, Life, PixelFormat, Redetect, TrackState, Tracker,
};
use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict};

/// The particle counts a `Tracker` can have. The core fixes N at compile
/// time, so each count is a `Tracker<N>` compiled into the module, another
/// copy of the tracker's code in the wheel: a few, doubling from a quarter
/// to four times the papers' 100, cover trading speed for accuracy. Each
/// method is written once here and expanded for every count.
macro_rules! particle_counts {
    ($($n:literal => $variant:ident),+ $(,)?) => {
        /// The counts built, smallest first.
        const PARTICLES: &[usize] = &[$($n),+];

        /// A tracker of one of the counts built. Boxed, so that a small
        /// tracker does not take the room of the largest.
        enum AnyTracker {
            $($variant(Box<Tracker<$n>>)),+
        }

        impl AnyTracker {
            /// A tracker of `particles`, or None for a count not built.
            fn new(particles: usize, config: Config, seed: u64) -> Option<Result<Self, Error>> {
                match particles {
                    $($n => Some(Tracker::<$n>::new(config, seed).map(|t| AnyTracker::$variant(Box::new(t)))),)+
                    _ => None,
                }
            }

            fn particles(&self) -> usize {
                match self {
                    $(AnyTracker::$variant(_) => $n),+
                }
            }

            fn init(&mut self, frame: &Frame<'_>, bbox: BoundingBox) -> Result<pftrack::Estimate, Error> {
                match self {
                    $(AnyTracker::$variant(t) => t.init(frame, bbox)),+
                }
            }

            fn step(&mut self, frame: &Frame<'_>) -> Result<pftrack::Estimate, Error> {
                match self {
                    $(AnyTracker::$variant(t) => t.step(frame)),+
                }
            }
        }
    };
}

particle_counts!(25 => P25, 50 => P50, 100 => P100, 200 => P200, 400 => P400);

/// The counts built, for messages: "25, 50, 100, 200 or 400".
fn counts_named() -> String {
    let names: Vec<String> = PARTICLES.iter().map(usize::to_string).collect();
    match names.split_last() {
        Some((last, rest)) if !rest.is_empty() => format!("{} or {last}", rest.join(", ")),
        _ => names.concat(),
    }
}

fn value_error(e: Error) -> PyErr {
    PyValueError::new_err(e.to_string())
}

/// What the last `init` or `update` found.
#[pyclass(module = "pftrack", frozen, get_all)]
#[derive(Clone)]
struct Estimate {
    /// The box, `(x, y, w, h)` in pixels.
    bbox: (f32, f32, f32, f32),
    /// The probability that the estimate is on the target, in `[0, 1]`.
    confidence: f32,
    /// `"searching"`, `"tracking"` or `"lost"`.
    state: &'static str,
    /// `None`, `"initialised"`, `"acquired"`, `"lost"` or `"reacquired"`.
    event: Option<&'static str>,
    /// The ellipse, `(cx, cy, half_width, half_height)`.
    ellipse: (f32, f32, f32, f32),
}

#[pymethods]
impl Estimate {
    fn __repr__(&self) -> String {
        let event = self.event.map_or_else(|| "None".to_string(), |e| format!("{e:?}"));
        format!("Estimate(bbox={:?}, confidence={}, state={:?}, event={event})", self.bbox, self.confidence, self.state)
    }
}

fn estimate_of(e: &pftrack::Estimate) -> Estimate {
    let b = e.bbox();
    Estimate {
        bbox: (b.x, b.y, b.width, b.height),
        confidence: e.confidence,
        state: match e.state {
            TrackState::Searching => "searching",
            TrackState::Tracking => "tracking",
            TrackState::Lost => "lost",
        },
        event: e.event.map(|v| match v {
            Event::Initialised => "initialised",
            Event::Acquired => "acquired",
            Event::LostTarget => "lost",
            Event::Reacquired => "reacquired",
        }),
        ellipse: (e.ellipse.cx, e.ellipse.cy, e.ellipse.hx, e.ellipse.hy),
    }
}

/// The pixels of one frame, borrowed where the array's layout is the
/// frame's (C-contiguous, in the tracker's channel order), else copied, and
/// how to read them.
struct Pixels<'a> {
    bytes: std::borrow::Cow<'a, [u8]>,
    width: usize,
    height: usize,
    stride: usize,
    format: PixelFormat,
}

impl Pixels<'_> {
    fn frame(&self) -> Result<Frame<'_>, Error> {
        Ok(Frame::new(&self.bytes, self.width, self.height, self.stride, self.format)?)
    }
}

fn format_named(name: &str) -> PyResult<PixelFormat> {
    Ok(match name {
        "rgb565" => PixelFormat::Rgb565,
        "rgb888" => PixelFormat::Rgb888,
        "yuyv" | "yuv422" => PixelFormat::Yuv422,
        "gray8" => PixelFormat::Gray8,
        "i420" => PixelFormat::I420,
        "nv12" => PixelFormat::Nv12,
        other => {
            return Err(PyValueError::new_err(format!(
                "unknown format {other:?}: rgb565, rgb888, yuyv, gray8, i420 or nv12"
            )));
        }
    })
}

/// A NumPy array borrowed read-only for the length of a call.
enum Array<'a> {
    Colour(PyReadonlyArray3<'a, u8>),
    Grey(PyReadonlyArray2<'a, u8>),
}

/// The frame `obj` holds: an `HxWx3` uint8 array (BGR, or RGB with `rgb`),
/// an `HxW` uint8 array (grey), or raw camera bytes with `raw` =
/// `(format, width, height, stride)`. Arrays are read through their strides.
fn pixels<'py, 'b>(
    obj: &Bound<'py, PyAny>,
    arrays: &'b mut Option<Array<'py>>,
    rgb: bool,
    raw: Option<(String, usize, usize, usize)>,
) -> PyResult<Pixels<'b>> {
    if let Some((format, width, height, stride)) = raw {
        let format = format_named(&format)?;
        let bytes = obj
            .cast::<PyBytes>()
            .map(|b| b.as_bytes().to_vec())
            .or_else(|_| obj.extract::<Vec<u8>>())
            .map_err(|_| PyTypeError::new_err("raw frames are bytes, bytearray or a uint8 buffer"))?;
        return Ok(Pixels { bytes: bytes.into(), width, height, stride, format });
    }
    if let Ok(a) = obj.extract::<PyReadonlyArray3<'py, u8>>() {
        let shape = a.shape();
        let (h, w, c) = (shape[0], shape[1], shape[2]);
        if c != 3 {
            return Err(PyTypeError::new_err(format!("a colour frame is HxWx3, not HxWx{c}")));
        }
        let Array::Colour(a) = arrays.insert(Array::Colour(a)) else {
            return Err(PyTypeError::new_err("a colour frame"));
        };
        let bytes = match (a.as_slice(), rgb) {
            // The array is the frame: no copy.
            (Ok(px), true) => px.into(),
            // OpenCV's BGR: the channels swapped, row by row.
            (Ok(px), false) => px.chunks_exact(3).flat_map(|p| [p[2], p[1], p[0]]).collect::<Vec<u8>>().into(),
            // A view with strides: read a pixel at a time.
            (Err(_), _) => {
                let mut bytes = Vec::with_capacity(h * w * 3);
                for row in a.as_array().outer_iter() {
                    for px in row.outer_iter() {
                        let (b0, b1, b2) = (px[0], px[1], px[2]);
                        bytes.extend_from_slice(&if rgb { [b0, b1, b2] } else { [b2, b1, b0] });
                    }
                }
                bytes.into()
            }
        };
        return Ok(Pixels { bytes, width: w, height: h, stride: w * 3, format: PixelFormat::Rgb888 });
    }
    if let Ok(a) = obj.extract::<PyReadonlyArray2<'py, u8>>() {
        let shape = a.shape();
        let (h, w) = (shape[0], shape[1]);
        let Array::Grey(a) = arrays.insert(Array::Grey(a)) else {
            return Err(PyTypeError::new_err("a grey frame"));
        };
        let bytes = match a.as_slice() {
            Ok(px) => px.into(),
            Err(_) => a.as_array().iter().copied().collect::<Vec<u8>>().into(),
        };
        return Ok(Pixels { bytes, width: w, height: h, stride: w, format: PixelFormat::Gray8 });
    }
    Err(PyTypeError::new_err(
        "a frame is a uint8 NumPy array, HxWx3 (BGR; RGB with rgb=True) or HxW (grey), or raw bytes with raw=(format, width, height, stride)",
    ))
}

/// The configuration from keyword settings over the one `config` names
/// (`"default"` unless given, which is `"accurate"`, `Config::accurate`;
/// `"fast"`: `Config::fast`), whatever the keywords' order.
fn config_of(settings: Option<&Bound<'_, PyDict>>) -> PyResult<Config> {
    let Some(settings) = settings else { return Ok(Config::default()) };
    let mut c = match settings.get_item("config")? {
        None => Config::default(),
        Some(v) => {
            let name = v.extract::<String>()?;
            let [a, b, f] = Config::NAMES;
            Config::named(&name).ok_or_else(|| {
                PyValueError::new_err(format!("config: {name:?} is not {a:?}, {b:?} or {f:?}"))
            })?
        }
    };
    let (mut lost_below, mut found_above) = match c.life {
        Life::Confidence { lost_below, found_above } => (lost_below, found_above),
        Life::Appearance => (0.6, 0.8),
    };
    for (key, value) in settings.iter() {
        let key: String = key.extract()?;
        match key.as_str() {
            "config" => {}
            "lost_below" => lost_below = value.extract()?,
            "found_above" => found_above = value.extract()?,
            "alpha" => c.alpha = value.extract()?,
            "lost_after" => c.lost_after = value.extract()?,
            "correlation" => {
                c.correlation = value.extract::<bool>()?.then_some(c.correlation.unwrap_or(CorrelationCue::MEASURED))
            }
            "scene_motion" => c.scene_motion = value.extract()?,
            "redetect" => {
                c.redetect = match value.extract::<String>()?.as_str() {
                    "off" => Redetect::Off,
                    "near" => Redetect::Near,
                    "frame" => Redetect::Frame,
                    other => {
                        return Err(PyValueError::new_err(format!(
                            "redetect: {other:?} is none of \"off\", \"near\", \"frame\""
                        )));
                    }
                }
            }
            "sure_share" => c.sure_share = value.extract()?,
            other => {
                return Err(PyTypeError::new_err(format!(
                    "unknown setting {other:?}: config, lost_below, found_above, alpha, lost_after, correlation, scene_motion, redetect, sure_share"
                )));
            }
        }
    }
    c.life = Life::Confidence { lost_below, found_above };
    Ok(c)
}

/// A colour particle-filter tracker with OpenCV's interface:
/// `Tracker(particles=100, seed=1, rgb=False, **settings)`, then
/// `init(frame, (x, y, w, h))` and `ok, box = update(frame)`. `particles`
/// is 25, 50, 100, 200 or 400.
#[pyclass(name = "Tracker", module = "pftrack")]
struct PyTracker {
    inner: AnyTracker,
    rgb: bool,
    last: Option<Estimate>,
}

#[pymethods]
impl PyTracker {
    #[new]
    #[pyo3(signature = (particles = 100, seed = 1, rgb = false, **settings))]
    fn new(particles: i64, seed: u64, rgb: bool, settings: Option<&Bound<'_, PyDict>>) -> PyResult<Self> {
        // Signed, so that a negative count is the same ValueError as any
        // other count not built rather than an OverflowError.
        let bad = || {
            PyValueError::new_err(format!("particles must be {} (the counts built), not {particles}", counts_named()))
        };
        let count = usize::try_from(particles).map_err(|_| bad())?;
        let inner = AnyTracker::new(count, config_of(settings)?, seed).ok_or_else(bad)?.map_err(value_error)?;
        Ok(PyTracker { inner, rgb, last: None })
    }

    /// The number of particles.
    #[getter]
    fn particles(&self) -> usize {
        self.inner.particles()
    }

    /// Learns the target in `box` of `frame` and tracks it from there (call
    /// again to re-initialise). Returns True, as OpenCV's `init` does.
    #[pyo3(signature = (frame, box_, raw = None))]
    fn init(
        &mut self,
        py: Python<'_>,
        frame: &Bound<'_, PyAny>,
        box_: (f32, f32, f32, f32),
        raw: Option<(String, usize, usize, usize)>,
    ) -> PyResult<bool> {
        let mut arrays = None;
        let px = pixels(frame, &mut arrays, self.rgb, raw)?;
        let (x, y, w, h) = box_;
        let tracker = &mut self.inner;
        let e = py
            .detach(|| px.frame().and_then(|f| tracker.init(&f, BoundingBox::new(x, y, w, h))))
            .map_err(value_error)?;
        self.last = Some(estimate_of(&e));
        Ok(true)
    }

    /// Tracks one frame: `(ok, (x, y, w, h))`, `ok` while the state is
    /// tracking. The GIL is released while the tracker runs.
    #[pyo3(signature = (frame, raw = None))]
    fn update(
        &mut self,
        py: Python<'_>,
        frame: &Bound<'_, PyAny>,
        raw: Option<(String, usize, usize, usize)>,
    ) -> PyResult<(bool, (f32, f32, f32, f32))> {
        let mut arrays = None;
        let px = pixels(frame, &mut arrays, self.rgb, raw)?;
        let tracker = &mut self.inner;
        let e = py.detach(|| px.frame().and_then(|f| tracker.step(&f))).map_err(value_error)?;
        let est = estimate_of(&e);
        let out = (est.state == "tracking", est.bbox);
        self.last = Some(est);
        Ok(out)
    }

    /// The last estimate (None before `init`).
    #[getter]
    fn estimate(&self) -> Option<Estimate> {
        self.last.clone()
    }
}

#[pymodule]
fn _pftrack(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyTracker>()?;
    m.add_class::<Estimate>()?;
    Ok(())
}
