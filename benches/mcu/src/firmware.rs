//! The bridge and the link it drives, as a firmware holds them: a module of each bench that
//! measures the bridge (`qemu_bench_mavlink`, `qemu_bench_signing`). Every call is in line,
//! so that what is measured is the bridge's own.
#![allow(dead_code)] // each bench uses some

use idu_gimbal::link::{Config, Link};
use idu_gimbal::Instant;
use idu_gimbal_mavlink::{Bridge, BridgeConfig, BridgeStats};

pub struct Fw {
    pub bridge: Bridge,
    pub link: Link,
}

impl Fw {
    /// `config` must be one [`Bridge::new`] takes: a bench's is, and one it refused would
    /// stop the bench at its first instruction.
    pub fn new(config: BridgeConfig) -> Self {
        Fw {
            bridge: Bridge::new(config.check().unwrap_or_else(|_| cortex_m::asm::udf())),
            link: Link::new(Config::default()),
        }
    }

    #[inline(always)]
    pub fn receive(&mut self, bytes: &[u8], now: Instant) -> usize {
        self.bridge.receive(&mut self.link, bytes, now)
    }

    #[inline(always)]
    pub fn poll(&mut self, now: Instant) {
        self.bridge.poll(&mut self.link, now)
    }

    #[inline(always)]
    pub fn transmit_bytes(&self) -> &[u8] {
        self.bridge.transmit_bytes()
    }

    #[inline(always)]
    pub fn transmit_written(&mut self, n: usize) {
        self.bridge.transmit_written(n)
    }

    #[inline(always)]
    pub fn stats(&self) -> BridgeStats {
        self.bridge.stats()
    }
}
