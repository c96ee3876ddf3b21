//! What the STM32F405 firmware programs (`src/bin/`) share: clocks, the millisecond tick and
//! CAN1 ([`board`]), USART2 receive into a ring ([`usart2_ring`]).
#![no_std]

pub mod board;
pub mod usart2_ring;
