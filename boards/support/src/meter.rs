//! SysTick as an instruction counter under QEMU `-icount shift=0` (see
//! `benches/mcu/src/bin/qemu_bench.rs` for the method), shared by the benchmarks.
//!
//! Every function but the calibration loop is `#[inline]` or generic, so that it is compiled
//! into the benchmark with the regions it measures: the calibration (the empty region, the
//! loop overhead) has to be compiled as the regions it corrects are. Compiled apart in this
//! crate, the per-call counts moved by 2 instructions.

use core::hint::black_box;
use cortex_m::peripheral::syst::SystClkSource;
use cortex_m::peripheral::SYST;

/// The largest SysTick reload value (24 bits).
const RELOAD: u32 = 0x00FF_FFFF;

pub struct Meter {
    syst: SYST,
    /// Instructions per tick as a fraction: `num / den`.
    num: u64,
    den: u64,
    /// Ticks of an empty timed region.
    empty: u32,
    /// Instructions per iteration of the benchmark loop with an empty body.
    loop_overhead: f32,
}

/// Exactly `2 * n + 1` instructions (for `n >= 1`): `subs` and `bne` per iteration,
/// plus the `mov` of the count.
#[inline(never)]
fn known_loop(n: u32) {
    // SAFETY: register-only arithmetic and a local branch.
    unsafe {
        core::arch::asm!(
            "1:",
            "subs {0}, {0}, #1",
            "bne 1b",
            inout(reg) n => _,
            options(nomem, nostack),
        );
    }
}

impl Meter {
    /// The meter on the core's SysTick, calibrated, its calibration said as the first line
    /// of benchmark `name`; the run ends (failed) if the core's peripherals are taken.
    #[inline]
    pub fn start(name: &str) -> Self {
        let Some(core) = cortex_m::Peripherals::take() else {
            crate::qemu::exit(false)
        };
        let m = Meter::new(core.SYST);
        crate::println!(
            "{}: {:.3} instructions per SysTick tick (calibrated), loop overhead {:.1} per iteration",
            name,
            m.instructions_per_tick(),
            m.loop_overhead()
        );
        m
    }

    #[inline]
    pub fn new(mut syst: SYST) -> Self {
        syst.disable_interrupt();
        syst.set_clock_source(SystClkSource::Core);
        syst.set_reload(RELOAD);
        syst.clear_current();
        syst.enable_counter();
        let mut m = Meter {
            syst,
            num: 1,
            den: 1,
            empty: 0,
            loop_overhead: 0.0,
        };
        m.empty = m.ticks(|| ());
        const N: u32 = 200_000;
        let t1 = m.ticks(|| known_loop(black_box(N)));
        let t2 = m.ticks(|| known_loop(black_box(2 * N)));
        m.num = 2 * u64::from(N);
        m.den = u64::from(t2 - t1);
        m.loop_overhead = m.per_iter(4096, |_| ());
        m
    }

    /// Instructions per SysTick tick.
    #[inline]
    pub fn instructions_per_tick(&self) -> f32 {
        self.num as f32 / self.den as f32
    }

    #[inline]
    pub fn loop_overhead(&self) -> f32 {
        self.loop_overhead
    }

    /// SysTick ticks spent in `f` (including the fixed cost of reading the counter).
    #[inline(always)]
    pub fn ticks<R>(&mut self, f: impl FnOnce() -> R) -> u32 {
        let _ = self.syst.has_wrapped(); // reading COUNTFLAG clears it
        let start = SYST::get_current();
        black_box(f());
        let end = SYST::get_current();
        if self.syst.has_wrapped() {
            println!("SysTick wrapped during a measurement: shorten it");
            crate::qemu::exit(false);
        }
        start.wrapping_sub(end)
    }

    #[inline]
    pub fn to_instructions(&self, ticks: f32) -> f32 {
        ticks * self.num as f32 / self.den as f32
    }

    /// Instructions spent in `f`, less the cost of an empty timed region.
    #[inline(always)]
    pub fn once<R>(&mut self, f: impl FnOnce() -> R) -> f32 {
        let t = self.ticks(f);
        self.to_instructions(t as f32 - self.empty as f32)
    }

    /// Instructions per call of `body` (loop overhead included), from `n` and `2n`
    /// iterations.
    pub fn per_iter(&mut self, n: u32, mut body: impl FnMut(u32)) -> f32 {
        let mut run = |count: u32| {
            for i in 0..black_box(count) {
                body(black_box(i));
            }
        };
        let t1 = self.ticks(|| run(n));
        let t2 = self.ticks(|| run(2 * n));
        self.to_instructions((t2 - t1) as f32) / n as f32
    }

    /// Instructions per call of `body`, loop overhead subtracted.
    pub fn per_op(&mut self, n: u32, body: impl FnMut(u32)) -> f32 {
        self.per_iter(n, body) - self.loop_overhead
    }
}
