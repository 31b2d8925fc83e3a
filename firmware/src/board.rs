//! What differs between the boards the firmware is built for: the frame
//! buffer that fits, the start-up, and the pan-tilt example's servos and
//! LED. The default is QEMU's `mps2-an386` (an FPGA image with 4 MiB of
//! SRAM); the `stm32f405` feature builds for the STM32F405RG, QEMU's
//! `netduinoplus2` (the chip's memory map in `boards/stm32f405/memory.x`),
//! and the `rp2040` feature for the RP2040 (built and audited; QEMU has no
//! model of it).
//! `.cargo/qemu-run` picks the QEMU board from where the ELF starts.

#[cfg(not(any(feature = "stm32f405", feature = "rp2040")))]
pub use mps2::*;
#[cfg(feature = "rp2040")]
pub use rp2040::*;
#[cfg(feature = "stm32f405")]
pub use stm32f405::*;

/// A servo channel whose commanded duty can be read back.
pub trait DutyReadback {
    /// The duty the channel holds.
    fn duty(&self) -> u16;
}

/// An LED whose commanded level can be read back.
pub trait LevelReadback {
    /// Whether the LED was last switched on.
    fn is_on(&self) -> bool;
}

#[cfg(not(any(feature = "stm32f405", feature = "rp2040")))]
mod mps2 {
    use core::convert::Infallible;
    use embedded_hal::digital::{ErrorType as PinErrorType, OutputPin};
    use embedded_hal::pwm::{ErrorType as PwmErrorType, SetDutyCycle};

    /// The board's name in the firmware's report.
    pub const NAME: &str = "mps2-an386 (Cortex-M4F, 4 MiB of SRAM)";
    /// The largest frame held: QVGA RGB565. Frames stream through it one at
    /// a time, so memory does not grow with the fixture's length.
    pub const FRAME_BYTES: usize = 320 * 240 * 2;
    /// Instructions per SysTick tick under `-icount shift=0`: the board's
    /// SysTick runs at 25 MHz and an instruction takes 1 ns.
    pub const INSTRUCTIONS_PER_TICK: Option<u32> = Some(40);

    /// Nothing to set up: QEMU's board starts ready.
    pub fn init() {}

    /// A PWM channel that remembers its duty: what a 50 Hz servo timer
    /// counting at 1 MHz would be given (20,000 ticks per period). The
    /// emulated board has no timer to drive.
    pub struct Servo {
        duty: u16,
    }

    impl PwmErrorType for Servo {
        type Error = Infallible;
    }

    impl SetDutyCycle for Servo {
        fn max_duty_cycle(&self) -> u16 {
            20_000
        }

        fn set_duty_cycle(&mut self, duty: u16) -> Result<(), Infallible> {
            self.duty = duty;
            Ok(())
        }
    }

    impl super::DutyReadback for Servo {
        fn duty(&self) -> u16 {
            self.duty
        }
    }

    /// A GPIO pin that remembers its level.
    pub struct Led {
        on: bool,
    }

    impl PinErrorType for Led {
        type Error = Infallible;
    }

    impl OutputPin for Led {
        fn set_low(&mut self) -> Result<(), Infallible> {
            self.on = false;
            Ok(())
        }

        fn set_high(&mut self) -> Result<(), Infallible> {
            self.on = true;
            Ok(())
        }
    }

    impl super::LevelReadback for Led {
        fn is_on(&self) -> bool {
            self.on
        }
    }

    /// The pan and tilt servos and the lock LED.
    pub fn head() -> Option<(Servo, Servo, Led)> {
        Some((Servo { duty: 0 }, Servo { duty: 0 }, Led { on: false }))
    }
}

#[cfg(feature = "stm32f405")]
mod stm32f405 {
    use core::convert::Infallible;
    use embedded_hal::digital::{ErrorType as PinErrorType, OutputPin};
    use stm32f4xx_hal::gpio::{Output, PA5};
    use stm32f4xx_hal::pac;
    use stm32f4xx_hal::prelude::*;
    use stm32f4xx_hal::rcc::{Config, Rcc};
    use stm32f4xx_hal::timer::PwmChannel;

    /// The board's name in the firmware's report.
    pub const NAME: &str = "STM32F405RG (netduinoplus2), 128 KiB of SRAM, 16 MHz HSI";
    /// The largest frame held: QVGA GRAY8 (76,800 B); QQVGA RGB565
    /// (38,400 B) fits too, QVGA RGB565 (153,600 B) does not, and such a
    /// fixture is refused at start.
    pub const FRAME_BYTES: usize = 320 * 240;
    /// Not counted here: the board's SysTick runs at 168 MHz of QEMU's
    /// virtual time, which is no whole number of instructions per tick
    /// under `-icount shift=0`. The mps2-an386 build counts them.
    pub const INSTRUCTIONS_PER_TICK: Option<u32> = None;

    /// The clocks as reset leaves them: the 16 MHz HSI, no PLL. With
    /// `Config::hsi()` the HAL's `freeze` waits on no ready bit (QEMU's RCC
    /// is a stub whose ready bits read 0, so a PLL or HSE set-up would hang).
    fn clocks(rcc: pac::RCC) -> Rcc {
        rcc.freeze(Config::hsi())
    }

    /// Sets the clocks up (see [`clocks`]).
    pub fn init() {
        if let Some(dp) = pac::Peripherals::take() {
            let _ = clocks(dp.RCC);
        }
    }

    /// A servo on a TIM2 PWM channel (QEMU models TIM2-TIM5).
    pub type Servo<const C: u8> = PwmChannel<pac::TIM2, C>;

    impl<const C: u8> super::DutyReadback for PwmChannel<pac::TIM2, C>
    where
        pac::TIM2: stm32f4xx_hal::timer::CPin<C>,
    {
        /// The channel's compare register, read back from the timer.
        fn duty(&self) -> u16 {
            self.get_duty()
        }
    }

    /// The lock LED on PA5, with the level it was last given: QEMU's GPIO
    /// is a stub (writes go nowhere, reads give 0), so the level is kept
    /// here, not read from the output data register.
    pub struct Led {
        pin: PA5<Output>,
        on: bool,
    }

    impl PinErrorType for Led {
        type Error = Infallible;
    }

    impl OutputPin for Led {
        fn set_low(&mut self) -> Result<(), Infallible> {
            self.pin.set_low();
            self.on = false;
            Ok(())
        }

        fn set_high(&mut self) -> Result<(), Infallible> {
            self.pin.set_high();
            self.on = true;
            Ok(())
        }
    }

    impl super::LevelReadback for Led {
        fn is_on(&self) -> bool {
            self.on
        }
    }

    /// The pan servo on TIM2 channel 1 (PA0), the tilt servo on channel 2
    /// (PA1), both at 50 Hz, and the lock LED on PA5.
    pub fn head() -> Option<(Servo<0>, Servo<1>, Led)> {
        let dp = pac::Peripherals::take()?;
        let mut rcc = clocks(dp.RCC);
        let gpioa = dp.GPIOA.split(&mut rcc);
        let (_, (pan, tilt, ..)) = dp.TIM2.pwm_hz(50.Hz(), &mut rcc);
        let (mut pan, mut tilt) = (pan.with(gpioa.pa0), tilt.with(gpioa.pa1));
        pan.enable();
        tilt.enable();
        Some((pan, tilt, Led { pin: gpioa.pa5.into_push_pull_output(), on: false }))
    }
}

#[cfg(feature = "rp2040")]
mod rp2040 {
    use rp2040_hal::{Watchdog, clocks::init_clocks_and_plls, pac};

    /// The board's name in the firmware's report.
    pub const NAME: &str = "RP2040 (264 KiB of SRAM), 125 MHz from a 12 MHz crystal";
    /// The largest frame held: QVGA RGB565, as on the emulated board
    /// (153,600 B; the RP2040's SRAM has room for it).
    pub const FRAME_BYTES: usize = 320 * 240 * 2;
    /// SysTick here runs at the core clock, one tick per cycle, not per
    /// instruction: no instruction count.
    pub const INSTRUCTIONS_PER_TICK: Option<u32> = None;
    /// A Raspberry Pi Pico's crystal.
    const XTAL_HZ: u32 = 12_000_000;

    /// The second-stage boot loader, for the W25Q080 flash of a Pico.
    #[unsafe(link_section = ".boot2")]
    #[used]
    pub static BOOT2: [u8; 256] = rp2040_boot2::BOOT_LOADER_W25Q080;

    /// The clocks: the system PLL at 125 MHz from the crystal (the HAL's
    /// standard set-up; it waits for the crystal and the PLLs to lock,
    /// which on the chip takes about a millisecond).
    pub fn init() {
        if let Some(mut dp) = pac::Peripherals::take() {
            let mut watchdog = Watchdog::new(dp.WATCHDOG);
            let _ = init_clocks_and_plls(
                XTAL_HZ,
                dp.XOSC,
                dp.CLOCKS,
                dp.PLL_SYS,
                dp.PLL_USB,
                &mut dp.RESETS,
                &mut watchdog,
            );
        }
    }
}
