//! `key=value` overrides of the tracker configuration, for the command line
//! and ablation runs. Every key names a [`pftrack::Config`] field; values are
//! validated by the core afterwards, so this only parses.

use pftrack::{
    Binning, Combination, Config, EdgeCue, Life, LostSearch, ModelUpdate, Redetect, Resampling, Sampling, Shape, Sigma,
    Similarity, SizeSearch,
};

/// Parses one key's value into the configuration; given the key, for its
/// error messages.
type Parse = fn(&mut Config, &str, &str) -> Result<(), String>;

/// A key `apply` understands: its name, what it sets (the help text), and
/// its parser.
pub struct Key {
    /// The name before the `=`.
    pub name: &'static str,
    /// What the key sets, and the values it takes.
    pub help: &'static str,
    parse: Parse,
}

const fn key(name: &'static str, help: &'static str, parse: Parse) -> Key {
    Key { name, help, parse }
}

/// The keys `apply` understands, with what they set and how they are read.
pub const KEYS: &[Key] = &[
    key(
        "config",
        "default | accurate | fast (the whole configuration, which the settings after it change: Config::default, which is Config::accurate, both filters; or Config::fast, the grey-level filter alone)",
        |c, k, v| {
            let [a, b, f] = Config::NAMES;
            *c = Config::named(v).ok_or_else(|| format!("{k}: `{v}` is not {a}, {b} or {f}"))?;
            Ok(())
        },
    ),
    key("sampling", "full | checkerboard | quarter", sampling),
    key("resampling", "multinomial | systematic", resampling),
    key("binning", "rgb8x8x8 | hsv8x8x4 | rgb4x4x4 | adaptive (Birgé–Rozenholc)", binning),
    key("quadrants", "on | off (four quadrant histograms, median similarity)", |c, k, v| {
        set(&mut c.quadrants, on_off(k, v))
    }),
    key("similarity", "bhattacharyya | intersection", similarity),
    key("shape", "gaussian | exponential (likelihood exp(-d²/2σ²) or exp(-d/σ))", shape),
    key("model_update", "confident | degraded:C:FRAMES (update when confidence < C·ρ₀)", model_update),
    key("max_samples", "most pixels read per region and cue, 0 = all", max_samples),
    key("edges", "off | BINS:THRESHOLD[:flat], e.g. 8:100:flat (flat: weak pixels get a bin)", edges),
    key(
        "strong_percent",
        "P: the edge threshold drops to what P% of the first box's pixels reach, if fewer reach it (0: fixed)",
        strong_percent,
    ),
    key("combination", "product | weighted:W (W = colour weight)", combination),
    key("boundary", "off | W (ellipse-boundary gradient cue with share W)", boundary),
    key("table", "off | SPACING (likelihood-table mode, grid spacing in px)", table),
    key("sigma", "fixed σ, e.g. 0.2", |c, k, v| set(&mut c.likelihood.sigma, num(k, v).map(Sigma::Fixed))),
    key("adaptive_sigma", "MIN:MAX, e.g. 0.02:0.5 (σ chosen per frame)", adaptive_sigma),
    key("spread_sigma", "SPREAD:MIN:MAX, e.g. 8:0.005:0.5 (σ from the particles' spread)", spread_sigma),
    key("eps", "likelihood floor ε", |c, k, v| set(&mut c.likelihood.eps, num(k, v))),
    key("position_noise", "fraction of target size per frame", |c, k, v| {
        set(&mut c.dynamics.position_noise, num(k, v))
    }),
    key("velocity_noise", "fraction of target size per frame", |c, k, v| {
        set(&mut c.dynamics.velocity_noise, num(k, v))
    }),
    key("velocity_decay", "v <- decay * v + noise; 1 = constant velocity", |c, k, v| {
        set(&mut c.dynamics.velocity_decay, num(k, v))
    }),
    key("speed_noise", "position noise at least this times the target's recent speed (px/frame)", |c, k, v| {
        set(&mut c.dynamics.speed_noise, num(k, v))
    }),
    key("scale_noise", "relative, per frame", |c, k, v| set(&mut c.dynamics.scale_noise, num(k, v))),
    key("alpha", "model adaptation rate", |c, k, v| set(&mut c.alpha, num(k, v))),
    key("update_threshold", "π_T", |c, k, v| set(&mut c.update_threshold, num(k, v))),
    key("update_sigma", "σ of the model-update gate", |c, k, v| set(&mut c.update_sigma, num(k, v))),
    key("appearance_sigmas", "k in ρ > μ + kσ", |c, k, v| set(&mut c.appearance_sigmas, num(k, v))),
    key("min_appearance", "floor of the appearance threshold", |c, k, v| set(&mut c.min_appearance, num(k, v))),
    key("kickoff", "b", |c, k, v| set(&mut c.kickoff, num(k, v))),
    key("lost_after", "frames", lost_after),
    key("reseed_fraction", "fraction re-drawn per frame while searching", |c, k, v| {
        set(&mut c.reseed_fraction, num(k, v))
    }),
    key("min_half_axis", "pixels", |c, k, v| set(&mut c.min_half_axis, num(k, v))),
    key("template", "off | WEIGHT:RATE (grey template cue, NCC, share WEIGHT, adaptation RATE)", template),
    key("life", "appearance | confidence:LOST:FOUND (what drives the tracking / lost states)", life),
    key("sure_share", "share of the particles observed after a confident frame, (0, 1]", |c, k, v| {
        set(&mut c.sure_share, num(k, v))
    }),
    key(
        "redetect",
        "off | near | frame (where a missed target is looked for: near its last place after a miss while its motion \
         is unknown or fast, and also over the frame while lost)",
        redetect,
    ),
    key(
        "lost_search",
        "frame | widening:GROWTH (where a lost target is looked for: anywhere, or within 4 of its larger half axes of \
         where it was last found, plus GROWTH half axes for each frame since)",
        lost_search,
    ),
    key(
        "scene_motion",
        "on | off (a box that moves with its surroundings counts as a miss, for a target seen to move)",
        |c, k, v| set(&mut c.scene_motion, on_off(k, v)),
    ),
    key(
        "size",
        "off | STEP:SIMILARITY:ASPECT_PULL:SCALE_PULL[:TEMPLATE] | STEP:SIMILARITY:scale:SCALE_PULL[:TEMPLATE] | \
         STEP:SIMILARITY",
        size,
    ),
    key("surroundings_rate", "adaptation rate of the surroundings' histogram", |c, k, v| {
        set(&mut c.surroundings_rate, num(k, v))
    }),
    key(
        "shift",
        "off | STEP:ROUNDS:SIMILARITY:TEMPLATE (position hill-climbed against the surroundings, steps of STEP box sizes)",
        shift,
    ),
    key(
        "correlation",
        "off | on | PADDING:RATE:LEARN_ABOVE:PULL[:SCALE_STEP:SCALE_PULL[:MIN_PSR[:CENTRE_BIAS]]] (correlation filter on the grey levels; on = 2:0.05:0.7:0.7:0.03:0.3:3:0.7)",
        correlation,
    ),
    key(
        "gradient",
        "off | on | RATE:LEARN_ABOVE:LEARN_EVERY:PULL:SCALE_STEP:SCALE_PULL:MIN_PSR:BLEND:RELEARN_BELOW:RELEARN_ABOVE[:PYRAMID_PULL:PYRAMID_LEARN_ABOVE[:GREY_PULL[:NARROW_ABOVE]]] (correlation filter on gradient channels over a wide window, and its scale pyramid, off when left out; GREY_PULL, the pull on grey-level video, PULL when left out; NARROW_ABOVE, the confidence after which the window narrows, 1 (never) when left out; on = 0.2:0.7:4:0.7:0.03:0.3:3:0:4:0.8:0.2:0.9:0.85:0.95)",
        gradient,
    ),
    key(
        "background_weight",
        "STRENGTH[:ABOVE] | off (colour model weighted against the surroundings; 1 is CBWH)",
        background_weight,
    ),
];

/// Applies one `key=value` setting to `c`.
pub fn apply(c: &mut Config, setting: &str) -> Result<(), String> {
    let (key, v) = setting.split_once('=').ok_or_else(|| format!("`{setting}`: expected key=value"))?;
    let (key, v) = (key.trim(), v.trim());
    match KEYS.iter().find(|k| k.name == key) {
        Some(k) => (k.parse)(c, key, v),
        None => {
            let known: Vec<&str> = KEYS.iter().map(|k| k.name).collect();
            Err(format!("unknown setting `{key}`; known: {}", known.join(", ")))
        }
    }
}

/// Stores a parsed value in its field.
fn set<T>(field: &mut T, value: Result<T, String>) -> Result<(), String> {
    *field = value?;
    Ok(())
}

fn num(key: &str, v: &str) -> Result<f32, String> {
    v.parse::<f32>().map_err(|_| format!("{key}: `{v}` is not a number"))
}

/// The value named `v` among `options`; the error lists the names.
fn choice<T: Copy>(key: &str, v: &str, options: &[(&str, T)]) -> Result<T, String> {
    if let Some(&(_, t)) = options.iter().find(|(name, _)| *name == v) {
        return Ok(t);
    }
    let names: Vec<&str> = options.iter().map(|(n, _)| *n).collect();
    Err(format!("{key}: `{v}` is not one of {}", names.join(", ")))
}

fn on_off(key: &str, v: &str) -> Result<bool, String> {
    choice(key, v, &[("on", true), ("off", false)])
}

fn sampling(c: &mut Config, key: &str, v: &str) -> Result<(), String> {
    let options = [("full", Sampling::Full), ("checkerboard", Sampling::Checkerboard), ("quarter", Sampling::Quarter)];
    set(&mut c.sampling, choice(key, v, &options))
}

fn redetect(c: &mut Config, key: &str, v: &str) -> Result<(), String> {
    let options = [("off", Redetect::Off), ("near", Redetect::Near), ("frame", Redetect::Frame)];
    set(&mut c.redetect, choice(key, v, &options))
}

fn lost_search(c: &mut Config, key: &str, v: &str) -> Result<(), String> {
    let search = match v.split_once(':') {
        Some(("widening", growth)) => LostSearch::Widening { growth: num(key, growth)? },
        _ if v == "frame" => LostSearch::Frame,
        _ => return Err(format!("{key}: `{v}`: expected frame or widening:GROWTH")),
    };
    set(&mut c.lost_search, Ok(search))
}

fn resampling(c: &mut Config, key: &str, v: &str) -> Result<(), String> {
    let options = [("multinomial", Resampling::Multinomial), ("systematic", Resampling::Systematic)];
    set(&mut c.resampling, choice(key, v, &options))
}

fn binning(c: &mut Config, key: &str, v: &str) -> Result<(), String> {
    let options = [
        ("rgb8x8x8", Binning::Rgb8x8x8),
        ("hsv8x8x4", Binning::Hsv8x8x4),
        ("rgb4x4x4", Binning::Rgb4x4x4),
        ("adaptive", Binning::Adaptive),
    ];
    set(&mut c.binning, choice(key, v, &options))
}

fn similarity(c: &mut Config, key: &str, v: &str) -> Result<(), String> {
    let options = [("bhattacharyya", Similarity::Bhattacharyya), ("intersection", Similarity::Intersection)];
    set(&mut c.similarity, choice(key, v, &options))
}

fn shape(c: &mut Config, key: &str, v: &str) -> Result<(), String> {
    let options = [("gaussian", Shape::Gaussian), ("exponential", Shape::Exponential)];
    set(&mut c.likelihood.shape, choice(key, v, &options))
}

fn model_update(c: &mut Config, key: &str, v: &str) -> Result<(), String> {
    c.model_update = if v == "confident" {
        ModelUpdate::Confident
    } else if let Some(rest) = v.strip_prefix("degraded:") {
        let (f, n) = rest.split_once(':').ok_or_else(|| format!("model_update: `{v}` is not degraded:C:FRAMES"))?;
        ModelUpdate::WhenDegraded {
            factor: num(key, f)?,
            frames: n.parse().map_err(|_| format!("model_update: `{n}` is not a frame count"))?,
        }
    } else {
        return Err(format!("model_update: `{v}` is not confident or degraded:C:FRAMES"));
    };
    Ok(())
}

fn strong_percent(c: &mut Config, _key: &str, v: &str) -> Result<(), String> {
    let p = v.parse().map_err(|_| format!("strong_percent: `{v}` is not a whole percentage"))?;
    match c.edges.as_mut() {
        Some(e) => e.strong_percent = p,
        None => return Err("strong_percent: the edge cue is off".into()),
    }
    Ok(())
}

fn max_samples(c: &mut Config, _key: &str, v: &str) -> Result<(), String> {
    set(&mut c.max_samples, v.parse().map_err(|_| format!("max_samples: `{v}` is not a whole number")))
}

fn edges(c: &mut Config, _key: &str, v: &str) -> Result<(), String> {
    c.edges = if v == "off" {
        None
    } else {
        let mut parts = v.split(':');
        let (b, t, flat) = (parts.next(), parts.next(), parts.next());
        let (Some(b), Some(t)) = (b, t) else {
            return Err(format!("edges: `{v}` is not off or BINS:THRESHOLD[:flat]"));
        };
        if !matches!(flat, None | Some("flat")) || parts.next().is_some() {
            return Err(format!("edges: `{v}` is not off or BINS:THRESHOLD[:flat]"));
        }
        Some(EdgeCue {
            bins: b.parse().map_err(|_| format!("edges: `{b}` is not a bin count"))?,
            threshold: t.parse().map_err(|_| format!("edges: `{t}` is not a threshold"))?,
            flat_bin: flat.is_some(),
            strong_percent: c.edges.or(Config::default().edges).map_or(0, |e| e.strong_percent),
        })
    };
    Ok(())
}

fn combination(c: &mut Config, key: &str, v: &str) -> Result<(), String> {
    c.combination = if v == "product" {
        Combination::Product
    } else if let Some(w) = v.strip_prefix("weighted:") {
        Combination::Weighted { colour: num(key, w)? }
    } else {
        return Err(format!("combination: `{v}` is not product or weighted:W"));
    };
    Ok(())
}

fn table(c: &mut Config, _key: &str, v: &str) -> Result<(), String> {
    c.table = if v == "off" {
        None
    } else {
        Some(pftrack::TableMode { spacing: v.parse().map_err(|_| format!("table: `{v}` is not off or a spacing"))? })
    };
    Ok(())
}

fn boundary(c: &mut Config, key: &str, v: &str) -> Result<(), String> {
    c.boundary = if v == "off" { None } else { Some(pftrack::BoundaryCue { weight: num(key, v)? }) };
    Ok(())
}

fn adaptive_sigma(c: &mut Config, key: &str, v: &str) -> Result<(), String> {
    let (lo, hi) = v.split_once(':').ok_or_else(|| format!("adaptive_sigma: `{v}` is not MIN:MAX"))?;
    c.likelihood.sigma = Sigma::Adaptive { min: num(key, lo)?, max: num(key, hi)? };
    Ok(())
}

fn spread_sigma(c: &mut Config, key: &str, v: &str) -> Result<(), String> {
    let p: Vec<&str> = v.split(':').collect();
    let [a, lo, hi] = p.as_slice() else { return Err(format!("spread_sigma: `{v}` is not SPREAD:MIN:MAX")) };
    c.likelihood.sigma = Sigma::Spread { spread: num(key, a)?, min: num(key, lo)?, max: num(key, hi)? };
    Ok(())
}

fn lost_after(c: &mut Config, _key: &str, v: &str) -> Result<(), String> {
    set(&mut c.lost_after, v.parse().map_err(|_| format!("lost_after: `{v}` is not a whole number")))
}

fn size(c: &mut Config, key: &str, v: &str) -> Result<(), String> {
    // (step, similarity, aspect searched, aspect pull, area pull, template)
    let (step, sim, aspect, ap, sp, t) = match v.split(':').collect::<Vec<_>>().as_slice() {
        ["off"] => {
            c.size = None;
            return Ok(());
        }
        [step, sim] => (*step, *sim, true, "0", "0", "0"),
        [step, sim, "scale", sp] => (*step, *sim, false, "0", *sp, "0"),
        [step, sim, "scale", sp, t] => (*step, *sim, false, "0", *sp, *t),
        [step, sim, ap, sp] => (*step, *sim, true, *ap, *sp, "0"),
        [step, sim, ap, sp, t] => (*step, *sim, true, *ap, *sp, *t),
        _ => {
            return Err(format!(
                "{key}: `{v}`: expected off, STEP:SIMILARITY:ASPECT_PULL:SCALE_PULL[:TEMPLATE], \
                 STEP:SIMILARITY:scale:SCALE_PULL[:TEMPLATE] or STEP:SIMILARITY (no pulls, no template)"
            ));
        }
    };
    c.size = Some(SizeSearch {
        step: num(key, step)?,
        similarity: num(key, sim)?,
        aspect,
        aspect_pull: num(key, ap)?,
        scale_pull: num(key, sp)?,
        template: num(key, t)?,
    });
    Ok(())
}

fn shift(c: &mut Config, key: &str, v: &str) -> Result<(), String> {
    c.shift = match v.split(':').collect::<Vec<_>>().as_slice() {
        ["off"] => None,
        [step, rounds, sim, template] => Some(pftrack::ShiftSearch {
            step: num(key, step)?,
            rounds: rounds.parse().map_err(|_| format!("{key}: `{rounds}` is not a whole number"))?,
            similarity: num(key, sim)?,
            template: num(key, template)?,
        }),
        _ => return Err(format!("{key}: `{v}`: expected off or STEP:ROUNDS:SIMILARITY:TEMPLATE")),
    };
    Ok(())
}

fn template(c: &mut Config, key: &str, v: &str) -> Result<(), String> {
    c.template = if v == "off" {
        None
    } else {
        let (w, r) = v.split_once(':').ok_or_else(|| format!("{key}: `{v}`: expected off or WEIGHT:RATE"))?;
        Some(pftrack::TemplateCue { weight: num(key, w)?, rate: num(key, r)? })
    };
    Ok(())
}

fn life(c: &mut Config, key: &str, v: &str) -> Result<(), String> {
    c.life = match v.split(':').collect::<Vec<_>>().as_slice() {
        ["appearance"] => Life::Appearance,
        ["confidence", lost, found] => Life::Confidence { lost_below: num(key, lost)?, found_above: num(key, found)? },
        _ => return Err(format!("{key}: `{v}`: expected appearance or confidence:LOST:FOUND")),
    };
    Ok(())
}

fn gradient(c: &mut Config, key: &str, v: &str) -> Result<(), String> {
    c.gradient = match v.split(':').collect::<Vec<_>>().as_slice() {
        ["off"] => None,
        ["on"] => Some(pftrack::GradientCue::MEASURED),
        [rate, above, every, pull, step, scale_pull, psr, blend, relearn_below, relearn_above, pyramid @ ..] => {
            // The pyramid's fields, off when left out; the pull on grey
            // video, the pull's when left out; the narrower window after a
            // sure frame, never when left out.
            let pull = num(key, pull)?;
            let (pyramid_pull, pyramid_learn_above, grey_pull, narrow_above) = match pyramid {
                [] => (0.0, 0.0, pull, 1.0),
                [p, a] => (num(key, p)?, num(key, a)?, pull, 1.0),
                [p, a, g] => (num(key, p)?, num(key, a)?, num(key, g)?, 1.0),
                [p, a, g, n] => (num(key, p)?, num(key, a)?, num(key, g)?, num(key, n)?),
                _ => {
                    return Err(format!(
                        "{key}: `{v}`: a scale pyramid needs PYRAMID_PULL:PYRAMID_LEARN_ABOVE[:GREY_PULL[:NARROW_ABOVE]]"
                    ));
                }
            };
            Some(pftrack::GradientCue {
                rate: num(key, rate)?,
                learn_above: num(key, above)?,
                learn_every: every
                    .parse()
                    .map_err(|_| format!("{key}: `{every}`: LEARN_EVERY is a count from 1 to 255"))?,
                pull,
                grey_pull,
                scale_step: num(key, step)?,
                scale_pull: num(key, scale_pull)?,
                min_psr: num(key, psr)?,
                blend: num(key, blend)?,
                relearn_below: num(key, relearn_below)?,
                relearn_above: num(key, relearn_above)?,
                pyramid_pull,
                pyramid_learn_above,
                narrow_above,
            })
        }
        _ => {
            return Err(format!(
                "{key}: `{v}`: expected off, on or RATE:LEARN_ABOVE:LEARN_EVERY:PULL:SCALE_STEP:SCALE_PULL:MIN_PSR:BLEND:RELEARN_BELOW:RELEARN_ABOVE[:PYRAMID_PULL:PYRAMID_LEARN_ABOVE[:GREY_PULL[:NARROW_ABOVE]]]"
            ));
        }
    };
    Ok(())
}

fn correlation(c: &mut Config, key: &str, v: &str) -> Result<(), String> {
    c.correlation = match v.split(':').collect::<Vec<_>>().as_slice() {
        ["off"] => None,
        ["on"] => Some(pftrack::CorrelationCue::MEASURED),
        [padding, rate, above, pull, scale @ ..] => {
            // The optional fields, each 0 (off) when left out.
            let scale = scale.iter().map(|s| num(key, s)).collect::<Result<Vec<_>, _>>()?;
            let (scale_step, scale_pull, min_psr, centre_bias) = match *scale.as_slice() {
                [] => (0.0, 0.0, 0.0, 0.0),
                [step, pull] => (step, pull, 0.0, 0.0),
                [step, pull, psr] => (step, pull, psr, 0.0),
                [step, pull, psr, bias] => (step, pull, psr, bias),
                _ => {
                    return Err(format!(
                        "{key}: `{v}`: a scale search needs SCALE_STEP:SCALE_PULL[:MIN_PSR[:CENTRE_BIAS]]"
                    ));
                }
            };
            Some(pftrack::CorrelationCue {
                padding: num(key, padding)?,
                rate: num(key, rate)?,
                learn_above: num(key, above)?,
                pull: num(key, pull)?,
                scale_step,
                scale_pull,
                min_psr,
                centre_bias,
            })
        }
        _ => {
            return Err(format!(
                "{key}: `{v}`: expected off, on or PADDING:RATE:LEARN_ABOVE:PULL[:SCALE_STEP:SCALE_PULL[:MIN_PSR[:CENTRE_BIAS]]]"
            ));
        }
    };
    Ok(())
}

fn background_weight(c: &mut Config, key: &str, v: &str) -> Result<(), String> {
    c.background_weight = match v.split(':').collect::<Vec<_>>().as_slice() {
        ["off"] => None,
        [s] => Some(pftrack::BackgroundWeight { strength: num(key, s)?, above: 0.0 }),
        [s, a] => Some(pftrack::BackgroundWeight { strength: num(key, s)?, above: num(key, a)? }),
        _ => return Err(format!("{key}: expected STRENGTH[:ABOVE] or off, got {v:?}")),
    };
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_listed_key_is_accepted() {
        // Reason: KEYS is the help text; each must be a real setting.
        for key in KEYS {
            let k = key.name;
            let v = match k {
                "sampling" => "quarter",
                "resampling" => "multinomial",
                "binning" => "hsv8x8x4",
                "quadrants" => "on",
                "similarity" => "intersection",
                "shape" => "exponential",
                "model_update" => "degraded:0.9:5",
                "table" => "2",
                "max_samples" => "300",
                "edges" => "4:60",
                "strong_percent" => "20",
                "combination" => "weighted:0.3",
                "adaptive_sigma" => "0.1:0.3",
                "spread_sigma" => "4:0.01:0.3",
                "lost_after" => "4",
                "size" => "0.05:2",
                "shift" => "0.1:2:1:0.5",
                "life" => "appearance",
                "redetect" => "frame",
                "lost_search" => "frame",
                "scene_motion" => "off",
                "correlation" => "off",
                "gradient" => "off",
                "config" => "fast",
                "background_weight" => "1",
                "template" => "0.3:0.05",
                _ => "0.07",
            };
            let mut c = Config::default();
            apply(&mut c, &format!("{k}={v}")).unwrap();
            assert_ne!(c, Config::default(), "{k} changed nothing");
        }
        assert!(apply(&mut Config::default(), "nope=1").is_err());
        assert!(apply(&mut Config::default(), "sigma").is_err());
        assert!(apply(&mut Config::default(), "sigma=abc").is_err());
    }

    #[test]
    fn every_on_the_help_spells_out_is_on() {
        // Reason: a help text that lists what `on` stands for must list
        // what `on` sets; the two are written apart, so this holds them
        // together for every key whose help spells `on` out.
        let mut spelt = 0;
        for k in KEYS {
            let Some((_, rest)) = k.help.split_once("on = ") else { continue };
            let fields = rest.split([')', ' ', ';']).next().unwrap();
            let (mut on, mut listed) = (Config::default(), Config::default());
            apply(&mut on, &format!("{}=on", k.name)).unwrap();
            apply(&mut listed, &format!("{}={fields}", k.name)).unwrap();
            assert_eq!(on, listed, "{}: `on` is not {fields}", k.name);
            spelt += 1;
        }
        assert_eq!(spelt, 2, "correlation and gradient spell `on` out");
    }

    #[test]
    fn the_gradient_filter_reads_its_fields_in_order() {
        // Reason: the help text's forms, field by field: `on` is the
        // fourteen fields it lists; thirteen never narrow the window,
        // twelve leave the pull on grey video at the pull too, ten leave
        // the pyramid off as well.
        let gradient = |v: &str| {
            let mut c = Config::default();
            apply(&mut c, &format!("gradient={v}")).map(|()| c.gradient)
        };
        let on = gradient("on").unwrap();
        assert_eq!(on, gradient("0.2:0.7:4:0.7:0.03:0.3:3:0:4:0.8:0.2:0.9:0.85:0.95").unwrap());
        assert_eq!(on.map(|g| (g.pull, g.grey_pull, g.narrow_above)), Some((0.7, 0.85, 0.95)));
        let g = gradient("0.2:0.7:4:0.7:0.03:0.3:3:0:4:0.8:0.2:0.9:0.85").unwrap().unwrap();
        assert_eq!((g.grey_pull, g.narrow_above), (0.85, 1.0));
        let g = gradient("0.2:0.7:4:0.6:0.03:0.3:3:0:4:0.8:0.2:0.9").unwrap().unwrap();
        assert_eq!((g.pull, g.grey_pull, g.pyramid_pull, g.pyramid_learn_above), (0.6, 0.6, 0.2, 0.9));
        let g = gradient("0.2:0.7:4:0.6:0.03:0.3:3:0:4:0.8").unwrap().unwrap();
        assert_eq!((g.grey_pull, g.pyramid_pull, g.pyramid_learn_above, g.narrow_above), (0.6, 0.0, 0.0, 1.0));
        assert!(gradient("0.2:0.7:4:0.6:0.03:0.3:3:0:4:0.8:0.2").is_err());
        assert!(gradient("0.2:0.7:4:0.6:0.03:0.3:3:0:4:0.8:0.2:0.9:0.85:0.9:1").is_err());
    }

    #[test]
    fn the_size_search_reads_its_fields_in_order() {
        // Reason: the help text's forms, field by field; the shorter forms
        // leave the template's weight at 0.
        let size = |v: &str| {
            let mut c = Config::default();
            apply(&mut c, &format!("size={v}")).map(|()| c.size)
        };
        let s = size("0.02:1:0.03:0.05:0.3").unwrap().unwrap();
        assert_eq!(
            (s.step, s.similarity, s.aspect, s.aspect_pull, s.scale_pull, s.template),
            (0.02, 1.0, true, 0.03, 0.05, 0.3)
        );
        let s = size("0.02:1:scale:0.05:0.2").unwrap().unwrap();
        assert_eq!((s.aspect, s.aspect_pull, s.scale_pull, s.template), (false, 0.0, 0.05, 0.2));
        assert_eq!(size("0.02:1:0.03:0.05").unwrap().unwrap().template, 0.0);
        assert_eq!(size("off").unwrap(), None);
        assert!(size("0.02:1:0.03:0.05:0.3:1").is_err());
    }
}
