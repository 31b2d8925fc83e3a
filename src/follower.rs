//! Following a target with a pan-tilt head: estimates in, servo commands out.
//!
//! A PD controller with a dead zone, as on the head-tracking paper's robot,
//! turns the estimate's offset from the frame centre into servo positions,
//! written through embedded-hal 1.0's [`SetDutyCycle`] (one PWM channel per
//! axis); an [`OutputPin`] LED shows whether the target is being tracked.
//! While the target is lost or searched for, the head holds its position.

use crate::error::Checks;
use crate::error::ConfigError;
use crate::estimate::{Estimate, TrackState};
use crate::scalar::{Real, clamp};
use embedded_hal::digital::OutputPin;
use embedded_hal::pwm::SetDutyCycle;

/// How the head follows.
#[derive(Copy, Clone, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct FollowerConfig {
    /// Proportional gain: servo travel (fraction of its range) per frame, per
    /// unit of offset (the offset is −1 at the frame's left or top edge, +1 at
    /// the right or bottom edge).
    pub kp: Real,
    /// Derivative gain, on the change of the offset since the last frame.
    pub kd: Real,
    /// Offsets smaller than this (same units) count as zero, so the head does
    /// not hunt around a target that is already centred. In `[0, 1)`.
    pub dead_zone: Real,
    /// Duty cycle, as a fraction of the PWM period, at one end of the servo's
    /// travel: 0.05 is a 1 ms pulse in a 20 ms (50 Hz) period.
    pub duty_min: Real,
    /// Duty cycle at the other end: 0.10 is a 2 ms pulse at 50 Hz.
    pub duty_max: Real,
    /// Reverse the pan axis (servo mounted the other way round).
    pub invert_pan: bool,
    /// Reverse the tilt axis.
    pub invert_tilt: bool,
}

impl Default for FollowerConfig {
    /// Gentle gains for a 30 fps camera and a standard hobby servo at 50 Hz.
    fn default() -> Self {
        FollowerConfig {
            kp: 0.05,
            kd: 0.02,
            dead_zone: 0.1,
            duty_min: 0.05,
            duty_max: 0.10,
            invert_pan: false,
            invert_tilt: false,
        }
    }
}

impl FollowerConfig {
    /// Checks every field against its documented range.
    pub fn validate(&self) -> Result<(), ConfigError> {
        let mut c = Checks::new();
        c.share("follower.kp", self.kp);
        c.share("follower.kd", self.kd);
        c.range("follower.dead_zone", self.dead_zone, 0.0, 0.99);
        c.share("follower.duty_min", self.duty_min);
        c.share("follower.duty_max", self.duty_max);
        c.result()
    }
}

/// A failure of the follower: one of the three peripherals, or the configuration.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub enum FollowerError<P, T, L> {
    /// The pan PWM channel failed.
    Pan(P),
    /// The tilt PWM channel failed.
    Tilt(T),
    /// The LED pin failed.
    Led(L),
    /// The configuration is invalid.
    Config(ConfigError),
}

/// The error type of a [`PanTilt`] over peripherals `P`, `T` and `L`.
pub type HeadError<P, T, L> = FollowerError<
    <P as embedded_hal::pwm::ErrorType>::Error,
    <T as embedded_hal::pwm::ErrorType>::Error,
    <L as embedded_hal::digital::ErrorType>::Error,
>;

/// A pan-tilt head that keeps the target centred.
///
/// ```
/// use pftrack::follower::{FollowerConfig, PanTilt};
/// # use pftrack::{Ellipse, Estimate, TrackState};
/// # use core::convert::Infallible;
/// # struct Pwm(u16);
/// # impl embedded_hal::pwm::ErrorType for Pwm { type Error = Infallible; }
/// # impl embedded_hal::pwm::SetDutyCycle for Pwm {
/// #     fn max_duty_cycle(&self) -> u16 { 1000 }
/// #     fn set_duty_cycle(&mut self, d: u16) -> Result<(), Infallible> { self.0 = d; Ok(()) }
/// # }
/// # struct Led;
/// # impl embedded_hal::digital::ErrorType for Led { type Error = Infallible; }
/// # impl embedded_hal::digital::OutputPin for Led {
/// #     fn set_low(&mut self) -> Result<(), Infallible> { Ok(()) }
/// #     fn set_high(&mut self) -> Result<(), Infallible> { Ok(()) }
/// # }
/// let mut head = PanTilt::new(Pwm(0), Pwm(0), Led, FollowerConfig::default())?;
/// // The target is at the left quarter of a 320x240 frame, at mid height.
/// let est = Estimate {
///     ellipse: Ellipse { cx: 80.0, cy: 120.0, hx: 20.0, hy: 20.0 },
///     confidence: 0.9, state: TrackState::Tracking, event: None,
///     appearing: 50, model_updated: true, sigma: 0.1, occluded_quadrant: None,
/// };
/// head.update(&est, 320, 240)?;
/// let (pan, tilt) = head.position();
/// assert!(pan < 0.5, "the head turned left");
/// assert_eq!(tilt, 0.5, "and did not tilt");
/// # Ok::<(), pftrack::follower::FollowerError<Infallible, Infallible, Infallible>>(())
/// ```
pub struct PanTilt<P, T, L> {
    pan: P,
    tilt: T,
    led: L,
    config: FollowerConfig,
    max_duty: (u16, u16),
    /// Servo positions in `[0, 1]`: pan 0 is full left, tilt 0 is full up.
    position: (Real, Real),
    /// The offsets of the last tracked frame, for the derivative term.
    last_offset: Option<(Real, Real)>,
}

impl<P: SetDutyCycle, T: SetDutyCycle, L: OutputPin> PanTilt<P, T, L> {
    /// Takes the two PWM channels and the LED, centres both servos and turns
    /// the LED off.
    pub fn new(pan: P, tilt: T, led: L, config: FollowerConfig) -> Result<Self, HeadError<P, T, L>> {
        config.validate().map_err(FollowerError::Config)?;
        let max_duty = (pan.max_duty_cycle(), tilt.max_duty_cycle());
        let mut head = PanTilt { pan, tilt, led, config, max_duty, position: (0.5, 0.5), last_offset: None };
        head.write_pan()?;
        head.write_tilt()?;
        head.led.set_low().map_err(FollowerError::Led)?;
        Ok(head)
    }

    /// The servo positions, each in `[0, 1]` (pan 0 = full left, tilt 0 = full up).
    pub fn position(&self) -> (Real, Real) {
        self.position
    }

    /// The peripherals, for reading back what was written (diagnostics,
    /// tests, a display of the servo commands).
    pub fn peripherals(&self) -> (&P, &T, &L) {
        (&self.pan, &self.tilt, &self.led)
    }

    /// Gives the peripherals back.
    pub fn release(self) -> (P, T, L) {
        (self.pan, self.tilt, self.led)
    }

    /// Moves the head towards the estimate in a `frame_width × frame_height`
    /// frame. The LED is on while the state is tracking; otherwise the head
    /// holds still. Only axes whose command changed are written.
    pub fn update(
        &mut self,
        estimate: &Estimate,
        frame_width: usize,
        frame_height: usize,
    ) -> Result<(), HeadError<P, T, L>> {
        if estimate.state != TrackState::Tracking {
            self.last_offset = None;
            return self.led.set_low().map_err(FollowerError::Led);
        }
        self.led.set_high().map_err(FollowerError::Led)?;
        let offset = |c: Real, size: usize| -> Real {
            let half = 0.5 * size.max(1) as Real;
            let o = clamp((c - half) / half, -1.0, 1.0);
            if o.abs() < self.config.dead_zone { 0.0 } else { o }
        };
        let now = (offset(estimate.ellipse.cx, frame_width), offset(estimate.ellipse.cy, frame_height));
        let last = self.last_offset.unwrap_or(now);
        self.last_offset = Some(now);
        let (kp, kd) = (self.config.kp, self.config.kd);
        let command = |o: Real, prev: Real, invert: bool| {
            let u = kp * o + kd * (o - prev);
            if invert { -u } else { u }
        };
        let (u_pan, u_tilt) =
            (command(now.0, last.0, self.config.invert_pan), command(now.1, last.1, self.config.invert_tilt));
        if u_pan != 0.0 {
            self.position.0 = clamp(self.position.0 + u_pan, 0.0, 1.0);
            self.write_pan()?;
        }
        if u_tilt != 0.0 {
            self.position.1 = clamp(self.position.1 + u_tilt, 0.0, 1.0);
            self.write_tilt()?;
        }
        Ok(())
    }

    fn duty(&self, position: Real, max: u16) -> u16 {
        let c = &self.config;
        let fraction = c.duty_min + position * (c.duty_max - c.duty_min);
        (clamp(fraction, 0.0, 1.0) * max as Real + 0.5) as u16
    }

    fn write_pan(&mut self) -> Result<(), HeadError<P, T, L>> {
        let d = self.duty(self.position.0, self.max_duty.0);
        self.pan.set_duty_cycle(d).map_err(FollowerError::Pan)
    }

    fn write_tilt(&mut self) -> Result<(), HeadError<P, T, L>> {
        let d = self.duty(self.position.1, self.max_duty.1);
        self.tilt.set_duty_cycle(d).map_err(FollowerError::Tilt)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Ellipse;
    use embedded_hal_mock::eh1::digital::{Mock as Pin, State, Transaction as PinT};
    use embedded_hal_mock::eh1::pwm::{Mock as Pwm, Transaction as PwmT};

    fn estimate(cx: Real, cy: Real, state: TrackState) -> Estimate {
        Estimate {
            ellipse: Ellipse { cx, cy, hx: 10.0, hy: 10.0 },
            confidence: 0.9,
            state,
            event: None,
            appearing: 50,
            model_updated: false,
            sigma: 0.1,
            occluded_quadrant: None,
        }
    }

    // Servo at the centre: duty (0.05 + 0.5 · 0.05) · 1000 = 75.
    const CENTRE: u16 = 75;

    fn start() -> Vec<PwmT> {
        vec![PwmT::max_duty_cycle(1000), PwmT::set_duty_cycle(CENTRE)]
    }

    /// Runs the default head over `frames` (centre x, centre y, state) in a
    /// 320x240 frame, expecting exactly the pan duties `pan_duties` after the
    /// centring write, no tilt write after it, and the LED states `led` after
    /// the initial "off". Returns the final position.
    fn drive(pan_duties: &[u16], led: &[State], frames: &[(Real, Real, TrackState)]) -> (Real, Real) {
        let mut pan_t = start();
        pan_t.extend(pan_duties.iter().map(|&d| PwmT::set_duty_cycle(d)));
        let mut led_t = vec![PinT::set(State::Low)];
        led_t.extend(led.iter().map(|&s| PinT::set(s)));
        let (mut pan, mut tilt, mut pin) = (Pwm::new(&pan_t), Pwm::new(&start()), Pin::new(&led_t));
        let mut head = PanTilt::new(pan.clone(), tilt.clone(), pin.clone(), FollowerConfig::default()).unwrap();
        for &(cx, cy, state) in frames {
            head.update(&estimate(cx, cy, state), 320, 240).unwrap();
        }
        pan.done();
        tilt.done();
        pin.done();
        head.position()
    }

    #[test]
    fn target_to_the_left_turns_the_pan_servo_left() {
        // Reason, by hand: the target's centre is at 80 of 320 px, offset −0.5;
        // the first frame has no derivative, so u = 0.05 · (−0.5) = −0.025 and
        // the pan position goes 0.5 → 0.475: duty (0.05 + 0.475 · 0.05) · 1000
        // = 73.75 → 74. The next frame, same offset: u = −0.025 again → 0.45,
        // duty 72.5 → 73 (rounded half up). Tilt is centred: never written.
        let tracked = (80.0, 120.0, TrackState::Tracking);
        let (pan, _) = drive(&[74, 73], &[State::High, State::High], &[tracked, tracked]);
        assert!(pan < 0.5);
    }

    #[test]
    fn derivative_term_reacts_to_motion() {
        // Reason, by hand: offsets −0.5 then −0.75: the second command is
        // 0.05 · (−0.75) + 0.02 · (−0.25) = −0.0425, position 0.475 → 0.4325,
        // duty 71.625 → 72.
        let frames = [(80.0, 120.0, TrackState::Tracking), (40.0, 120.0, TrackState::Tracking)];
        drive(&[74, 72], &[State::High, State::High], &frames);
    }

    #[test]
    fn inside_the_dead_zone_nothing_moves() {
        // Reason: an offset of 0.05 (168 of 320 px) is under the 0.1 dead
        // zone on both axes: no duty is written, only the LED goes on.
        let position = drive(&[], &[State::High], &[(168.0, 126.0, TrackState::Tracking)]);
        assert_eq!(position, (0.5, 0.5));
    }

    #[test]
    fn lost_holds_position_and_turns_the_led_off() {
        // Reason: while lost the estimate is not the target; the head must not
        // chase it. The target far to the right writes nothing, LED low.
        let frames = [(310.0, 10.0, TrackState::Lost), (310.0, 10.0, TrackState::Searching)];
        let position = drive(&[], &[State::Low, State::Low], &frames);
        assert_eq!(position, (0.5, 0.5));
    }

    #[test]
    fn bad_config_is_refused_before_touching_the_hardware() {
        let (mut pan, mut tilt, mut led) = (Pwm::new(&[]), Pwm::new(&[]), Pin::new(&[]));
        let cfg = FollowerConfig { kp: Real::NAN, ..FollowerConfig::default() };
        let r = PanTilt::new(pan.clone(), tilt.clone(), led.clone(), cfg);
        assert!(matches!(r, Err(FollowerError::Config(ConfigError { field: "follower.kp", .. }))));
        let cfg = FollowerConfig { dead_zone: 1.0, ..FollowerConfig::default() };
        let r = PanTilt::new(pan.clone(), tilt.clone(), led.clone(), cfg);
        assert!(matches!(r, Err(FollowerError::Config(ConfigError { field: "follower.dead_zone", .. }))));
        pan.done();
        tilt.done();
        led.done();
    }
}
