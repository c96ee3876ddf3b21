//! idu-gimbal under embassy on QEMU's `netduinoplus2` (an emulated STM32F405): the sans-IO
//! [`Link`] driven by an async task, as in `boards/embassy_stm32f405`, against the crate's
//! simulated gimbal, playing the scripted session of `idu_firmware_support::session` in real
//! (virtual) embassy time.
//!
//! embassy-stm32 cannot boot there (see `boards/embassy_stm32f405/examples/qemu_probe.rs`:
//! no RCC, TIM2-5 raise no compare flags, no CAN), but embassy itself can:
//!
//! * **Time**: embassy-time on the Cortex-M SysTick ([`time_driver`]), which QEMU models,
//!   at 1 kHz from the 168 MHz system clock.
//! * **Executor**: embassy-executor's raw executor in a thread-mode loop that sleeps in
//!   `WFI` ([`main`]). The stock thread executor sleeps in `WFE`, which QEMU 7.2 runs as a
//!   no-op (it yields to its main loop and returns): it would spin through every idle
//!   millisecond, and under `-icount` spinning is virtual time burnt instruction by
//!   instruction (measured: the same session, with the same output, takes 24 s of host
//!   time on `embassy_executor::Executor` against 0.4 s here). `WFI` halts, and
//!   `-icount sleep=off` jumps to the next SysTick.
//! * **CAN** is replaced by two embassy-sync channels of frames, one each way, with
//!   `idu_gimbal::sim::Simulator` on the other side ([`gimbal_task`]).
//!
//! Tasks:
//!
//! * [`link_task`] owns the [`Link`] and sleeps until the first of: a received frame, the
//!   link's [`Link::next_deadline`], vehicle data or a request from the session, room on the
//!   bus (only while frames wait for it). Never on a fixed period.
//! * [`vehicle_task`] sends vehicle data at 10 Hz through a channel (a stand-in autopilot).
//! * [`gimbal_task`] runs the simulated gimbal: it takes the link's frames as they come and
//!   steps every millisecond (its slew and its 500 ms postbacks).
//! * [`session_task`] plays the script (`idu_firmware_support::session::steps`, the one the
//!   synchronous player plays), checks each step's effect on the simulator's state
//!   and the postbacks, prints telemetry through semihosting, and exits QEMU through
//!   semihosting `SYS_EXIT`: 0 only if every check passed, 1 otherwise (and on a panic or a
//!   HardFault).
//!
//! Run: `./run.sh` (installs the target and QEMU when missing), or `cargo run --release`
//! in this directory.
#![no_std]
#![no_main]

mod time_driver;

use core::cell::RefCell;
use core::sync::atomic::{AtomicBool, Ordering};

use cortex_m_rt::entry;
use embassy_executor::{raw, Spawner};
use embassy_futures::select::{select, select4, Either, Either4};
use embassy_sync::blocking_mutex::raw::CriticalSectionRawMutex;
use embassy_sync::blocking_mutex::Mutex;
use embassy_sync::channel::Channel;
use embassy_time::{Duration, Ticker, Timer};

use idu_gimbal::link::{Config, Event, Link, LinkStats};
use idu_gimbal::sim::{SimConfig, Simulator};
use idu_gimbal::wire::control::{GimbalCommand, Rate};
use idu_gimbal::wire::postback::Postback;
use idu_gimbal::wire::Frame;
use idu_gimbal::Instant;
// The conversion between embassy-time and the core's clock, as the STM32F405 board does it.
use idu_firmware_support::embassy::{embassy_at, next_wake, tick};
use idu_firmware_support::vehicle::Vehicle;

// ---- output and exit ----

// Semihosting output (`println!`), `exit`, and the panic and HardFault handlers (status 1):
// the support the repository's other QEMU firmware uses.
use idu_firmware_support::println;
use idu_firmware_support::qemu::{exit, Stdout};
// The script and what a player says, shared with the synchronous player (`Script`).
use idu_firmware_support::session::{
    self, say_event, say_fail, say_ok, say_postback, say_verdict, steps, vehicle_frames_verdict,
    Check, Step, RATE_HOLD, TEXT,
};

// ---- what the tasks exchange ----

/// Frames on the emulated bus, link to gimbal: a CAN controller's three transmit
/// mailboxes.
static TO_GIMBAL: Channel<CriticalSectionRawMutex, Frame, 3> = Channel::new();
/// Frames on the emulated bus, gimbal to link: a receive queue (a postback is 4 frames).
static TO_LINK: Channel<CriticalSectionRawMutex, Frame, 16> = Channel::new();

static VEHICLE: Channel<CriticalSectionRawMutex, Vehicle, 4> = Channel::new();

/// What the session asks of the link.
#[derive(Clone, Copy)]
enum Request {
    Command(GimbalCommand),
    Rate(Rate),
    Text(&'static [u8]),
    Stats,
}

static REQUESTS: Channel<CriticalSectionRawMutex, Request, 4> = Channel::new();

/// What the link tells the session.
#[derive(Clone, Copy)]
enum Report {
    Event(Event),
    /// A new postback, and whether the link is up.
    Postback(Postback, bool),
    /// A request the link refused (its queue was full).
    Refused,
    Stats(LinkStats, LinkTaskStats),
}

static REPORTS: Channel<CriticalSectionRawMutex, Report, 16> = Channel::new();

/// The simulated gimbal, stepped by [`gimbal_task`] and inspected by the session's checks.
static SIM: Mutex<CriticalSectionRawMutex, RefCell<Option<Simulator>>> =
    Mutex::new(RefCell::new(None));

/// Runs `f` on the simulator's state.
fn with_sim<R>(f: impl FnOnce(&Simulator) -> R) -> Option<R> {
    SIM.lock(|sim| sim.borrow().as_ref().map(f))
}

// ---- the link task ----

/// How the link task spent its time.
#[derive(Clone, Copy, Default)]
struct LinkTaskStats {
    /// Times it woke up.
    wakeups: u32,
    /// Times the bus had no room for a frame (the link kept it, and the task waited for
    /// room).
    bus_full: u32,
    /// Reports the session had no room for (none expected: it always listens).
    reports_lost: u32,
}

fn report(stats: &mut LinkTaskStats, r: Report) {
    if REPORTS.try_send(r).is_err() {
        stats.reports_lost = stats.reports_lost.wrapping_add(1);
    }
}

/// Hands the link's frames to the bus until it is full.
fn transmit(link: &mut Link, stats: &mut LinkTaskStats) {
    while let Some(frame) = link.next_transmit() {
        match TO_GIMBAL.try_send(frame) {
            Ok(()) => link.transmit_done(None),
            Err(_) => {
                link.transmit_refused(frame);
                stats.bus_full = stats.bus_full.wrapping_add(1);
                return;
            }
        }
    }
}

/// Drives the link: never returns.
#[embassy_executor::task]
async fn link_task() {
    let mut link: Link = Link::new(Config::default());
    let max_rx = link.config().max_rx_per_poll.get();
    let mut stats = LinkTaskStats::default();

    loop {
        let at = embassy_time::Instant::now();
        let now = tick(at);
        link.poll(now);
        if link.has_transmit() {
            transmit(&mut link, &mut stats);
        }
        while let Some(event) = link.next_event() {
            let r = match event {
                Event::Postback => match link.latest_postback(now) {
                    Some((p, _age)) => Report::Postback(p, link.is_link_up()),
                    None => continue,
                },
                other => Report::Event(other),
            };
            report(&mut stats, r);
        }

        // Sleep until the first of: a frame, the link's deadline, vehicle data or a
        // request, room on the bus (only while frames wait for it).
        let deadline = next_wake(&link, now);
        let waiting = link.has_transmit();
        let room = async {
            if waiting {
                core::future::poll_fn(|cx| TO_GIMBAL.poll_ready_to_send(cx)).await
            } else {
                core::future::pending().await
            }
        };
        let woke = select4(
            TO_LINK.receive(),
            Timer::at(embassy_at(deadline, at)),
            select(VEHICLE.receive(), REQUESTS.receive()),
            room,
        )
        .await;
        stats.wakeups = stats.wakeups.wrapping_add(1);
        let now = tick(embassy_time::Instant::now());
        match woke {
            Either4::First(frame) => {
                link.receive(frame.id, &frame.data, now);
                // And those queued behind it, at most `max_rx_per_poll` in all.
                for _ in 1..max_rx {
                    let Ok(frame) = TO_LINK.try_receive() else {
                        break;
                    };
                    link.receive(frame.id, &frame.data, now);
                }
            }
            Either4::Second(()) | Either4::Fourth(()) => {}
            Either4::Third(Either::First(sample)) => {
                sample.push(&mut link);
            }
            Either4::Third(Either::Second(request)) => {
                let refused = match request {
                    Request::Command(command) => link.send(command).is_err(),
                    Request::Rate(rate) => link.set_rate(rate, now).is_err(),
                    Request::Text(text) => link.send_text(text).is_err(),
                    Request::Stats => {
                        let task = stats;
                        report(&mut stats, Report::Stats(link.stats(), task));
                        false
                    }
                };
                if refused {
                    report(&mut stats, Report::Refused);
                }
            }
        }
    }
}

// ---- the vehicle data ----

/// Stand-in vehicle data at 10 Hz, as `idu_firmware_support::session` pushes it: level,
/// heading 30°, hovering over Zurich at 450 m.
#[embassy_executor::task]
async fn vehicle_task() {
    let mut ticker = Ticker::every(Duration::from_millis(100));
    loop {
        if let Some(v) = session::vehicle(tick(embassy_time::Instant::now())) {
            VEHICLE.send(v).await;
        }
        ticker.next().await;
    }
}

// ---- the simulated gimbal ----

/// The gimbal on the other side of the bus: takes frames as they come, steps every
/// millisecond, and puts its postback frames on the bus while it has room.
#[embassy_executor::task]
async fn gimbal_task() {
    let mut ticker = Ticker::every(Duration::from_millis(1));
    loop {
        let now = tick(embassy_time::Instant::now());
        SIM.lock(|sim| {
            let mut sim = sim.borrow_mut();
            let Some(sim) = sim.as_mut() else {
                return;
            };
            while let Ok(frame) = TO_GIMBAL.try_receive() {
                // A frame the gimbal rejects is counted in its stats.
                let _ = sim.receive(frame.id, &frame.data, now);
            }
            let _ = sim.poll(now);
            while !TO_LINK.is_full() {
                let Some(frame) = sim.pop_frame() else {
                    break;
                };
                let _ = TO_LINK.try_send(frame);
            }
        });
        select(TO_GIMBAL.ready_to_receive(), ticker.next()).await;
    }
}

// ---- the session ----

/// The script's player over the link task's channels: the newest postback, its clock and
/// its failures. It plays `idu_firmware_support::session`'s steps ([`steps`]) and says what
/// it sees as the synchronous player (`Script`) does.
struct Player {
    start: embassy_time::Instant,
    out: Stdout,
    latest: Option<Postback>,
    stats: Option<(LinkStats, LinkTaskStats)>,
    failures: u32,
}

impl Player {
    fn elapsed_ms(&self) -> u64 {
        self.start.elapsed().as_millis()
    }

    /// Takes one report; true for a new postback.
    fn handle(&mut self, r: Report) -> bool {
        match r {
            Report::Postback(p, up) => {
                self.latest = Some(p);
                let elapsed = self.elapsed_ms();
                say_postback(&mut self.out, elapsed, &p, up);
                return true;
            }
            Report::Event(event) => say_event(&mut self.out, event),
            Report::Refused => {
                self.failures += 1;
                println!("  FAIL queue full");
            }
            Report::Stats(link, task) => self.stats = Some((link, task)),
        }
        false
    }

    /// Takes reports until `end`.
    async fn run_until(&mut self, end: embassy_time::Instant) {
        while let Either::First(r) = select(REPORTS.receive(), Timer::at(end)).await {
            self.handle(r);
        }
    }

    async fn run(&mut self, ms: u32) {
        self.run_until(embassy_time::Instant::now() + Duration::from_millis(ms.into()))
            .await;
    }

    /// Waits until `check` holds on a postback received after this call, or `timeout_ms`.
    async fn expect(&mut self, what: &str, timeout_ms: u32, check: Check) {
        let end = embassy_time::Instant::now() + Duration::from_millis(timeout_ms.into());
        while let Either::First(r) = select(REPORTS.receive(), Timer::at(end)).await {
            if !self.handle(r) {
                continue;
            }
            let Some(p) = self.latest else {
                continue;
            };
            if with_sim(|sim| check(&p, sim.state())) == Some(true) {
                let elapsed = self.elapsed_ms();
                say_ok(&mut self.out, what, elapsed);
                return;
            }
        }
        self.failures += 1;
        say_fail(&mut self.out, what, timeout_ms);
    }

    async fn request(&mut self, r: Request) {
        REQUESTS.send(r).await;
    }

    async fn rate_hold(&mut self) {
        let hold = RATE_HOLD;
        hold.say_start(&mut self.out);
        let before = self.latest.map_or(0, |p| p.motor_heading);
        if let Ok(rate) = Rate::new(hold.yaw_dps, 0.0) {
            let start = embassy_time::Instant::now();
            for i in 1..=hold.refreshes {
                self.request(Request::Rate(rate)).await;
                let at = u64::from(hold.refresh_ms * i);
                self.run_until(start + Duration::from_millis(at)).await;
            }
        }
        self.run(hold.release_ms).await;
        let after = with_sim(|s| s.state().motor_yaw_deg);
        self.run(hold.settle_ms).await;
        let later = with_sim(|s| s.state().motor_yaw_deg);
        let stopped = with_sim(|s| s.state().rate == (0.0, 0.0)) == Some(true);
        let turned = i32::from(self.latest.map_or(0, |p| p.motor_heading)) - i32::from(before);
        let looks = after.zip(later);
        if !hold.verdict(&mut self.out, turned, looks, stopped) {
            self.failures += 1;
        }
    }

    /// Plays the script; returns the number of checks that failed.
    async fn play(&mut self) -> u32 {
        println!(
            "idu-gimbal session: embassy link task <-> simulated gimbal over embassy-sync channels"
        );
        // The emulated bus carries vehicle frames: headings north-referenced.
        for step in steps(true) {
            match step {
                Step::Command(what, command) => {
                    println!("> {}", what);
                    self.request(Request::Command(command)).await;
                }
                Step::Expect(what, timeout_ms, check) => self.expect(what, timeout_ms, check).await,
                Step::RateHold => self.rate_hold().await,
                Step::Text(timeout_ms) => {
                    println!("> text message");
                    self.request(Request::Text(TEXT)).await;
                    self.expect("text received", timeout_ms, |_, s| {
                        s.last_text.as_bytes() == TEXT
                    })
                    .await;
                }
            }
        }

        // The link's counters, through the request channel like everything else.
        self.request(Request::Stats).await;
        let asked = embassy_time::Instant::now();
        while self.stats.is_none() && asked.elapsed() < Duration::from_millis(100) {
            if let Either::First(r) = select(
                REPORTS.receive(),
                Timer::at(asked + Duration::from_millis(100)),
            )
            .await
            {
                self.handle(r);
            }
        }
        let elapsed_ms = self.elapsed_ms();
        match self.stats {
            Some((s, task)) => {
                println!(
                    "frames sent {} received {}; postbacks {}; superseded vehicle frames {}",
                    s.frames_sent, s.frames_received, s.postbacks, s.superseded
                );
                println!(
                    "link task woke {} times in {} ms; bus full {} times; reports lost {}",
                    task.wakeups, elapsed_ms, task.bus_full, task.reports_lost
                );
                if task.reports_lost != 0 {
                    self.failures += 1;
                    println!("  FAIL reports lost");
                }
            }
            None => {
                self.failures += 1;
                println!("  FAIL no stats from the link task");
            }
        }
        match with_sim(|s| s.stats()) {
            // Vehicle frames reach the gimbal: the emulated bus carries them.
            Some(sim) if vehicle_frames_verdict(&mut self.out, &sim, true) => {}
            _ => self.failures += 1,
        }
        say_verdict(&mut self.out, self.failures);
        self.failures
    }
}

/// Plays the session, then ends the emulation with its result.
#[embassy_executor::task]
async fn session_task() {
    let mut player = Player {
        start: embassy_time::Instant::now(),
        out: Stdout::default(),
        latest: None,
        stats: None,
        failures: 0,
    };
    let failures = player.play().await;
    exit(failures == 0)
}

// ---- start-up and the thread-mode loop ----

/// Set by the executor when a task is woken; cleared before each poll.
static PENDED: AtomicBool = AtomicBool::new(false);

/// The executor's pender: a task was woken (from a task or an interrupt).
#[export_name = "__pender"]
fn pender(_context: *mut ()) {
    PENDED.store(true, Ordering::Release);
}

fn spawn_all(spawner: Spawner) -> Result<(), embassy_executor::SpawnError> {
    spawner.spawn(link_task()?);
    spawner.spawn(vehicle_task()?);
    spawner.spawn(gimbal_task()?);
    spawner.spawn(session_task()?);
    Ok(())
}

#[entry]
fn main() -> ! {
    static mut EXECUTOR: Option<raw::Executor> = None;

    println!("embassy_qemu: STM32F405 (QEMU netduinoplus2), embassy-executor with a SysTick time driver at 1 kHz");
    let Some(core) = cortex_m::Peripherals::take() else {
        println!("embassy_qemu: core peripherals already taken");
        exit(false)
    };
    SIM.lock(|sim| {
        *sim.borrow_mut() = Some(Simulator::new(
            SimConfig::default(),
            Instant::from_millis(0),
        ))
    });
    time_driver::start(core.SYST);

    let executor: &'static raw::Executor =
        EXECUTOR.insert(raw::Executor::new(core::ptr::null_mut()));
    if spawn_all(executor.spawner()).is_err() {
        println!("embassy_qemu: could not spawn the tasks");
        exit(false)
    }
    loop {
        PENDED.store(false, Ordering::Release);
        // SAFETY: this loop is the only caller of `poll`, never re-entered (the pender only
        // sets a flag).
        unsafe { executor.poll() };
        // Sleep unless a task was woken meanwhile. With interrupts masked a wake-up cannot
        // slip in between the check and WFI; a pending interrupt still ends WFI, and runs
        // once they are unmasked.
        cortex_m::interrupt::free(|_| {
            if !PENDED.load(Ordering::Acquire) {
                cortex_m::asm::wfi();
            }
        });
    }
}
