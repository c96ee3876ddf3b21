use super::*;
use embedded_can::blocking;
use embedded_can::nb::Can;
use embedded_can::Frame;

fn ext(id: u32) -> MockFrame {
    MockFrame::extended(id, &id.to_le_bytes()).unwrap()
}

fn std_frame(id: u16) -> MockFrame {
    MockFrame::standard(id, &[id as u8]).unwrap()
}

fn nb_err(kind: ErrorKind) -> nb::Error<MockError> {
    nb::Error::Other(MockError::new(kind))
}

#[test]
fn frame_implements_the_frame_trait() {
    let sid = StandardId::new(0x7FF).unwrap();
    let f = MockFrame::new(sid, &[1, 2, 3]).unwrap();
    assert!(f.is_standard() && !f.is_extended());
    assert!(f.is_data_frame() && !f.is_remote_frame());
    assert_eq!(f.id(), Id::Standard(sid));
    assert_eq!((f.dlc(), f.data()), (3, &[1u8, 2, 3][..]));
    assert_eq!(f.raw_id(), 0x7FF);

    let eid = ExtendedId::new(0x1FFF_FFFF).unwrap();
    let f = MockFrame::new(eid, &[0; 8]).unwrap();
    assert!(f.is_extended());
    assert_eq!(f.id(), Id::Extended(eid));
    assert_eq!(f.dlc(), 8);
    assert_eq!(MockFrame::new(eid, &[0; 9]), None);
    assert_eq!(MockFrame::new(eid, &[]).unwrap().data(), &[] as &[u8]);

    let r = MockFrame::new_remote(eid, 5).unwrap();
    assert!(r.is_remote_frame() && !r.is_data_frame());
    assert_eq!((r.dlc(), r.data()), (5, &[] as &[u8]));
    assert_eq!(MockFrame::new_remote(sid, 9), None);
    assert_ne!(r, MockFrame::new(eid, &[0; 5]).unwrap());

    // Range checks of the helpers.
    assert_eq!(MockFrame::standard(0x800, &[]), None);
    assert!(MockFrame::standard(0x7FF, &[]).is_some());
    assert_eq!(MockFrame::extended(0x2000_0000, &[]), None);
    assert_eq!(MockFrame::extended(0x1FFF_FFFF, &[0; 9]), None);
    let e = MockFrame::extended(0x0000_0F01, &[9; 8]).unwrap();
    assert_eq!(
        e,
        MockFrame::new(ExtendedId::new(0xF01).unwrap(), &[9; 8]).unwrap()
    );
    // Same raw id, different format: different frames.
    assert_ne!(
        MockFrame::extended(0x100, &[]).unwrap(),
        MockFrame::standard(0x100, &[]).unwrap()
    );
}

#[test]
fn arbitration_key_follows_can_arbitration() {
    let sid = |id| StandardId::new(id).unwrap();
    let eid = |id| ExtendedId::new(id).unwrap();
    let key = |f: MockFrame| f.arbitration_key();
    // Within a format: lower id wins, data beats remote.
    assert!(key(ext(0x10)) < key(ext(0x11)));
    assert!(key(std_frame(0x10)) < key(std_frame(0x11)));
    let d = MockFrame::new(eid(0x55), &[]).unwrap();
    let r = MockFrame::new_remote(eid(0x55), 0).unwrap();
    assert!(key(d) < key(r));
    let d = MockFrame::new(sid(0x55), &[]).unwrap();
    let r = MockFrame::new_remote(sid(0x55), 0).unwrap();
    assert!(key(d) < key(r));
    // A standard frame beats an extended one with the same 11-bit base id, even as a
    // remote frame; but equal *raw* ids put the extended frame's base at 0.
    assert!(key(std_frame(0x100)) < key(ext(0x100 << 18)));
    assert!(key(MockFrame::new_remote(sid(0x100), 0).unwrap()) < key(ext(0x100 << 18)));
    assert!(key(ext(0x100 << 18)) < key(MockFrame::new_remote(eid(0x100 << 18), 0).unwrap()));
    assert!(key(ext(0x100)) < key(std_frame(0x100)));
    // Mixed formats compare on the 11-bit base id first.
    assert!(key(std_frame(0x001)) < key(ext(0x0004_0000)));
    assert!(key(ext(0x0004_0000)) < key(std_frame(0x002)));
    assert!(key(ext(0x0003_FFFF)) < key(std_frame(0x001)));
    assert!(key(std_frame(0x7FF)) < key(ext(0x1FFF_FFFF)));
}

#[test]
fn broadcast_reaches_every_other_endpoint_not_the_sender() {
    let bus: Bus<4, 4> = Bus::new(1);
    let mut a = bus.endpoint(0).unwrap();
    let mut b = bus.endpoint(1).unwrap();
    let mut c = bus.endpoint(2).unwrap();
    let f = ext(0x123);
    assert_eq!(a.transmit(&f), Ok(None));
    assert_eq!(b.receive(), Ok(f));
    assert_eq!(c.receive(), Ok(f));
    assert_eq!(a.receive(), Err(nb::Error::WouldBlock));
    assert_eq!(b.receive(), Err(nb::Error::WouldBlock));
    // Endpoint 3 joins only now: it did not get the earlier frame, but gets later ones.
    let mut d = bus.endpoint(3).unwrap();
    assert_eq!(d.receive(), Err(nb::Error::WouldBlock));
    let g = ext(0x456);
    assert_eq!(c.transmit(&g), Ok(None));
    assert_eq!(a.receive(), Ok(g));
    assert_eq!(b.receive(), Ok(g));
    assert_eq!(d.receive(), Ok(g));
    assert_eq!(c.receive(), Err(nb::Error::WouldBlock));
    let s = bus.stats();
    assert_eq!((s.sent, s.delivered), (2, 5));
    assert_eq!(bus.pending(), 0);
}

#[test]
fn rx_fifo_keeps_transmission_order() {
    let bus: Bus<2, 8> = Bus::new(1);
    let mut a = bus.endpoint(0).unwrap();
    let mut b = bus.endpoint(1).unwrap();
    // Descending priority order and mixed formats: auto-delivery sends each at once.
    let frames = [
        ext(0x500),
        std_frame(0x7),
        ext(0x400),
        ext(0x1),
        std_frame(0x300),
    ];
    for f in &frames {
        assert_eq!(a.transmit(f), Ok(None));
    }
    for f in &frames {
        assert_eq!(b.receive(), Ok(*f));
    }
    assert_eq!(b.receive(), Err(nb::Error::WouldBlock));
}

#[test]
fn full_mailboxes_displace_lower_priority_or_would_block() {
    let bus: Bus<2, 8> = Bus::new(1);
    bus.set_auto_deliver(false);
    let mut a = bus.endpoint(0).unwrap();
    let mut b = bus.endpoint(1).unwrap();
    for id in [0x10, 0x30, 0x20] {
        assert_eq!(a.transmit(&ext(id)), Ok(None));
    }
    assert_eq!(bus.pending(), 3);
    // 0x25 beats the lowest-priority pending frame, 0x30, which comes back.
    assert_eq!(a.transmit(&ext(0x25)), Ok(Some(ext(0x30))));
    // Nothing pending has lower priority than these (equal ids are not displaced).
    assert_eq!(a.transmit(&ext(0x40)), Err(nb::Error::WouldBlock));
    assert_eq!(a.transmit(&ext(0x25)), Err(nb::Error::WouldBlock));
    // Data beats remote of the same id.
    let remote = MockFrame::new_remote(ExtendedId::new(0x25).unwrap(), 0).unwrap();
    assert_eq!(a.transmit(&remote), Err(nb::Error::WouldBlock));
    // Mixed formats: standard 0x000 beats every pending extended frame (base id 0,
    // then IDE), so it displaces the lowest of them, extended 0x25.
    assert_eq!(a.transmit(&std_frame(0x000)), Ok(Some(ext(0x25))));
    // Standard 0x001 (base 1) loses to all pending extended frames (base 0).
    assert_eq!(a.transmit(&std_frame(0x001)), Err(nb::Error::WouldBlock));
    assert_eq!(b.receive(), Err(nb::Error::WouldBlock));
    assert_eq!(bus.deliver(), 3);
    for f in [std_frame(0x000), ext(0x10), ext(0x20)] {
        assert_eq!(b.receive(), Ok(f));
    }
    assert_eq!(b.receive(), Err(nb::Error::WouldBlock));
    let s = bus.stats();
    assert_eq!((s.sent, s.displaced, s.delivered), (3, 2, 3));
    // Accepted = 3 + 2 displacing transmits = sent + displaced + pending.
    assert_eq!(bus.pending(), 0);

    // A remote frame pending is displaced by the data frame of the same id.
    bus.set_mailboxes(0, 1);
    assert_eq!(a.transmit(&remote), Ok(None));
    assert_eq!(a.transmit(&ext(0x25)), Ok(Some(remote)));
}

#[test]
fn deliver_one_sends_highest_priority_first_across_endpoints() {
    let bus: Bus<3, 8> = Bus::new(1);
    bus.set_auto_deliver(false);
    let mut a = bus.endpoint(0).unwrap();
    let mut b = bus.endpoint(1).unwrap();
    let mut c = bus.endpoint(2).unwrap();
    assert_eq!(a.transmit(&ext(0x300)), Ok(None));
    assert_eq!(a.transmit(&ext(0x100)), Ok(None));
    assert_eq!(b.transmit(&ext(0x200)), Ok(None));
    assert_eq!(c.transmit(&ext(0x050)), Ok(None));
    assert_eq!(b.transmit(&ext(0x200)), Ok(None)); // same id: after the first
    assert_eq!(c.receive(), Err(nb::Error::WouldBlock));

    assert_eq!(bus.deliver_one(), Some(ext(0x050)));
    assert_eq!(a.receive(), Ok(ext(0x050)));
    assert_eq!(b.receive(), Ok(ext(0x050)));
    assert_eq!(c.receive(), Err(nb::Error::WouldBlock));
    assert_eq!(bus.pending(), 4);

    assert_eq!(bus.deliver_one(), Some(ext(0x100)));
    assert_eq!(bus.deliver_one(), Some(ext(0x200)));
    assert_eq!(bus.deliver_one(), Some(ext(0x200)));
    assert_eq!(bus.deliver_one(), Some(ext(0x300)));
    assert_eq!(bus.deliver_one(), None);
    assert_eq!(bus.deliver(), 0);
    for f in [ext(0x100), ext(0x200), ext(0x200), ext(0x300)] {
        assert_eq!(c.receive(), Ok(f));
    }
    // Turning auto-delivery back on flushes pending frames.
    assert_eq!(a.transmit(&ext(0x1)), Ok(None));
    assert_eq!(bus.pending(), 1);
    bus.set_auto_deliver(true);
    assert_eq!(bus.pending(), 0);
    assert_eq!(c.receive(), Ok(ext(0x1)));
}

#[test]
fn mailbox_count_is_configurable() {
    let bus: Bus<2, 8> = Bus::new(1);
    bus.set_auto_deliver(false);
    assert!(!bus.set_mailboxes(0, 0));
    assert!(!bus.set_mailboxes(0, MAX_MAILBOXES + 1));
    assert!(!bus.set_mailboxes(2, 1));
    assert!(bus.set_mailboxes(0, MAX_MAILBOXES));
    let mut a = bus.endpoint(0).unwrap();
    for id in 0..MAX_MAILBOXES as u32 {
        assert_eq!(a.transmit(&ext(0x100 + id)), Ok(None));
    }
    assert_eq!(a.transmit(&ext(0x200)), Err(nb::Error::WouldBlock));
    // Fewer mailboxes than pending frames: full until enough are delivered.
    assert!(bus.set_mailboxes(0, 2));
    assert_eq!(a.transmit(&ext(0x200)), Err(nb::Error::WouldBlock));
    for _ in 0..MAX_MAILBOXES - 1 {
        assert!(bus.deliver_one().is_some());
    }
    assert_eq!(a.transmit(&ext(0x200)), Ok(None));
    assert_eq!(a.transmit(&ext(0x201)), Err(nb::Error::WouldBlock));
}

#[test]
fn overrun_is_reported_once_and_keeps_queued_frames() {
    let bus: Bus<2, 2> = Bus::new(1);
    let mut a = bus.endpoint(0).unwrap();
    let mut b = bus.endpoint(1).unwrap();
    for id in 1..=4 {
        assert_eq!(a.transmit(&ext(id)), Ok(None));
    }
    assert_eq!(b.receive(), Err(nb_err(ErrorKind::Overrun)));
    assert_eq!(b.receive(), Ok(ext(1)));
    assert_eq!(b.receive(), Ok(ext(2)));
    assert_eq!(b.receive(), Err(nb::Error::WouldBlock));
    let s = bus.stats();
    assert_eq!((s.sent, s.delivered, s.overruns), (4, 2, 2));
    // After draining, no further overrun.
    assert_eq!(a.transmit(&ext(5)), Ok(None));
    assert_eq!(b.receive(), Ok(ext(5)));
    assert_eq!(b.receive(), Err(nb::Error::WouldBlock));
}

/// Runs a fixed mixed workload and records everything the receivers saw.
fn workload(seed: u64) -> (std::vec::Vec<nb::Result<MockFrame, MockError>>, BusStats) {
    let faults = Faults {
        loss: 0.1,
        corruption: 0.2,
        duplication: 0.1,
        tx_error: 0.05,
        rx_error: 0.05,
    };
    let bus: Bus<3, 4> = Bus::new(seed).with_faults(faults);
    let mut eps = [
        bus.endpoint(0).unwrap(),
        bus.endpoint(1).unwrap(),
        bus.endpoint(2).unwrap(),
    ];
    let mut seen = std::vec::Vec::new();
    for i in 0..300u32 {
        let k = (i % 3) as usize;
        let r = eps[k].transmit(&ext(i)).map(|_| ext(u32::MAX >> 3));
        seen.push(r);
        for ep in eps.iter_mut() {
            seen.push(ep.receive());
        }
    }
    (seen, bus.stats())
}

#[test]
fn same_seed_and_faults_give_the_same_run() {
    let (run1, stats1) = workload(7);
    let (run2, stats2) = workload(7);
    assert_eq!(run1, run2);
    assert_eq!(stats1, stats2);
    assert!(stats1.lost > 0 && stats1.corrupted > 0 && stats1.duplicated > 0);
    assert!(stats1.injected_errors > 0);
    // The seed matters.
    let (run3, _) = workload(8);
    assert_ne!(run1, run3);
}

#[test]
fn wire_fault_rates_and_counters_add_up() {
    const N: u32 = 10_000;
    let bus: Bus<3, 4> = Bus::new(0xC0FFEE).with_faults(Faults {
        loss: 0.05,
        corruption: 0.05,
        duplication: 0.05,
        ..Faults::NONE
    });
    let mut a = bus.endpoint(0).unwrap();
    let mut rx = [bus.endpoint(1).unwrap(), bus.endpoint(2).unwrap()];
    let mut received = [0u32; 2];
    let mut altered = [std::vec::Vec::new(), std::vec::Vec::new()];
    for i in 0..N {
        let data = [i as u8, (i >> 8) as u8, 0xA5, 0x5A, 0xFF, 0, 0x0F, 0xF0];
        let f = MockFrame::extended(i, &data).unwrap();
        assert_eq!(a.transmit(&f), Ok(None));
        for (r, ep) in rx.iter_mut().enumerate() {
            while let Ok(g) = ep.receive() {
                received[r] += 1;
                assert_eq!(g.raw_id(), i);
                if g != f {
                    let flipped: u32 = g
                        .data()
                        .iter()
                        .zip(f.data())
                        .map(|(x, y)| (x ^ y).count_ones())
                        .sum();
                    assert_eq!(flipped, 1, "corruption flips exactly one bit");
                    altered[r].push(i);
                }
            }
        }
    }
    let s = bus.stats();
    assert_eq!(s.sent, N);
    assert!((400..600).contains(&s.lost), "lost {}", s.lost);
    assert!(
        (380..580).contains(&s.corrupted),
        "corrupted {}",
        s.corrupted
    );
    assert!(
        (380..580).contains(&s.duplicated),
        "duplicated {}",
        s.duplicated
    );
    assert_eq!(s.overruns, 0);
    // Every frame not lost reaches both receivers once, twice if duplicated.
    assert_eq!(
        s.delivered + s.overruns,
        (s.sent - s.lost + s.duplicated) * 2
    );
    assert_eq!(received, [s.delivered / 2, s.delivered / 2]);
    // Corruption is decided per frame: both receivers saw the same frames altered.
    altered[0].dedup();
    altered[1].dedup();
    assert_eq!(altered[0], altered[1]);
    assert_eq!(altered[0].len() as u32, s.corrupted);
    assert_eq!(s.injected_errors, 0);
}

#[test]
fn overruns_are_accounted_for_under_faults() {
    let bus: Bus<3, 3> = Bus::new(99).with_faults(Faults {
        loss: 0.1,
        duplication: 0.3,
        ..Faults::NONE
    });
    let mut a = bus.endpoint(0).unwrap();
    let mut b = bus.endpoint(1).unwrap();
    let _c = bus.endpoint(2).unwrap(); // never reads: overruns
    let mut got = 0u32;
    let mut drain = |b: &mut Endpoint<'_, 3, 3>| loop {
        match b.receive() {
            Ok(_) => got += 1,
            Err(nb::Error::WouldBlock) => break,
            Err(e) => assert_eq!(e, nb_err(ErrorKind::Overrun)),
        }
    };
    for i in 0..1000 {
        assert_eq!(a.transmit(&ext(i)), Ok(None));
        if i % 2 == 0 {
            drain(&mut b);
        }
    }
    drain(&mut b);
    let s = bus.stats();
    assert!(s.overruns > 900, "{s:?}");
    assert_eq!(
        s.delivered + s.overruns,
        (s.sent - s.lost + s.duplicated) * 2
    );
    // b read all its frames; c never read and holds exactly QUEUE of them.
    assert_eq!(s.delivered, got + 3);
}

#[test]
fn corruption_flips_exactly_one_data_bit() {
    let bus: Bus<2, 4> = Bus::new(5).with_faults(Faults {
        corruption: 1.0,
        ..Faults::NONE
    });
    let mut a = bus.endpoint(0).unwrap();
    let mut b = bus.endpoint(1).unwrap();
    let mut bytes_hit = [false; 8];
    for i in 0..200u32 {
        let len = (i % 8 + 1) as usize;
        let data = [0x00, 0xFF, 0x55, 0xAA, 0x0F, 0xF0, 0x12, 0x34];
        let f = MockFrame::extended(0x100, &data[..len]).unwrap();
        a.transmit(&f).unwrap();
        let g = b.receive().unwrap();
        assert_eq!((g.raw_id(), g.is_extended(), g.dlc()), (0x100, true, len));
        let diffs: std::vec::Vec<(usize, u8)> = g
            .data()
            .iter()
            .zip(f.data())
            .enumerate()
            .filter(|(_, (x, y))| x != y)
            .map(|(k, (x, y))| (k, x ^ y))
            .collect();
        assert_eq!(diffs.len(), 1);
        assert_eq!(diffs[0].1.count_ones(), 1);
        bytes_hit[diffs[0].0] = true;
    }
    assert!(bytes_hit.iter().all(|&hit| hit), "flips land in every byte");
    // And on every one of a full frame's 64 bits: 1,000 frames of zeros, each with the one
    // bit it got set (about 16 a bit; seeded, so the same run every time).
    let mut bits_hit = [false; 64];
    for _ in 0..1000 {
        a.transmit(&MockFrame::extended(0x100, &[0; 8]).unwrap())
            .unwrap();
        let g = b.receive().unwrap();
        let word = u64::from_le_bytes(g.data().try_into().unwrap());
        assert_eq!(word.count_ones(), 1);
        bits_hit[word.trailing_zeros() as usize] = true;
    }
    assert!(bits_hit.iter().all(|&hit| hit), "flips land on every bit");
    // Frames without data bits are never corrupted nor counted.
    let empty = MockFrame::extended(0x100, &[]).unwrap();
    let remote = MockFrame::new_remote(ExtendedId::new(0x100).unwrap(), 8).unwrap();
    for f in [empty, remote] {
        a.transmit(&f).unwrap();
        assert_eq!(b.receive(), Ok(f));
    }
    assert_eq!(bus.stats().corrupted, 1200);
}

#[test]
fn duplication_and_loss_and_mid_run_changes() {
    let bus: Bus<2, 4> = Bus::new(5).with_faults(Faults {
        duplication: 1.0,
        ..Faults::NONE
    });
    let mut a = bus.endpoint(0).unwrap();
    let mut b = bus.endpoint(1).unwrap();
    a.transmit(&ext(1)).unwrap();
    assert_eq!(b.receive(), Ok(ext(1)));
    assert_eq!(b.receive(), Ok(ext(1)));
    assert_eq!(b.receive(), Err(nb::Error::WouldBlock));
    bus.set_faults(Faults {
        loss: 1.0,
        ..Faults::NONE
    });
    assert_eq!(bus.faults().loss, 1.0);
    a.transmit(&ext(2)).unwrap();
    assert_eq!(b.receive(), Err(nb::Error::WouldBlock));
    bus.set_faults(Faults::default());
    a.transmit(&ext(3)).unwrap();
    assert_eq!(b.receive(), Ok(ext(3)));
    let s = bus.stats();
    assert_eq!((s.sent, s.lost, s.duplicated, s.delivered), (3, 1, 1, 3));
}

#[test]
fn error_fault_rates_and_kinds() {
    let bus: Bus<2, 4> = Bus::new(3).with_faults(Faults {
        tx_error: 0.1,
        rx_error: 0.1,
        ..Faults::NONE
    });
    let mut a = bus.endpoint(0).unwrap();
    let mut b = bus.endpoint(1).unwrap();
    let (mut tx_errors, mut rx_errors, mut received) = (0u32, 0u32, 0u32);
    for i in 0..10_000 {
        match a.transmit(&ext(i)) {
            Ok(None) => {}
            Err(nb::Error::Other(e)) => {
                assert!(TX_ERROR_KINDS.contains(&e.kind), "{e:?}");
                tx_errors += 1;
            }
            other => panic!("{other:?}"),
        }
        // Drain: an rx error consumes no frame, so keep going until WouldBlock.
        loop {
            match b.receive() {
                Ok(_) => received += 1,
                Err(nb::Error::WouldBlock) => break,
                Err(nb::Error::Other(e)) => {
                    assert!(RX_ERROR_KINDS.contains(&e.kind), "{e:?}");
                    rx_errors += 1;
                }
            }
        }
    }
    let s = bus.stats();
    assert!((800..1200).contains(&tx_errors), "tx errors {tx_errors}");
    // Receive is called about 10 000 + rx_errors + received times.
    assert!((1800..2600).contains(&rx_errors), "rx errors {rx_errors}");
    assert_eq!(s.injected_errors, tx_errors + rx_errors);
    assert_eq!(s.sent, 10_000 - tx_errors);
    // Nothing is lost to an rx error: every delivered frame was received.
    assert_eq!(received, s.delivered);
    assert_eq!(received, s.sent);
}

#[test]
fn injected_errors_reach_the_caller_exactly_once() {
    let bus: Bus<2, 4> = Bus::new(1);
    let mut a = bus.endpoint(0).unwrap();
    let mut b = bus.endpoint(1).unwrap();
    for kind in [
        ErrorKind::Bit,
        ErrorKind::Acknowledge,
        ErrorKind::Other,
        ErrorKind::Overrun,
    ] {
        a.inject_error(kind);
        assert_eq!(a.transmit(&ext(1)), Err(nb_err(kind)));
        assert_eq!(b.receive(), Err(nb::Error::WouldBlock), "frame not queued");
        assert_eq!(a.transmit(&ext(2)), Ok(None));
        b.inject_error(kind);
        assert_eq!(b.receive(), Err(nb_err(kind)));
        assert_eq!(b.receive(), Ok(ext(2)), "frame kept");
    }
    // Through the bus, and through the blocking API.
    assert!(bus.inject_error(1, ErrorKind::Crc));
    assert!(!bus.inject_error(2, ErrorKind::Crc));
    assert_eq!(
        blocking::Can::receive(&mut b),
        Err(MockError::new(ErrorKind::Crc))
    );
    assert!(bus.inject_error(0, ErrorKind::Stuff));
    assert_eq!(
        blocking::Can::transmit(&mut a, &ext(3)),
        Err(MockError::new(ErrorKind::Stuff))
    );
    assert_eq!(bus.stats().injected_errors, 10);
    // An injected error comes before a pending overrun.
    for i in 0..5 {
        a.transmit(&ext(i)).unwrap();
    }
    b.inject_error(ErrorKind::Form);
    assert_eq!(b.receive(), Err(nb_err(ErrorKind::Form)));
    assert_eq!(b.receive(), Err(nb_err(ErrorKind::Overrun)));
    assert_eq!(b.receive(), Ok(ext(0)));
    // Display and the Error trait.
    let e = MockError::new(ErrorKind::Crc);
    assert_eq!(embedded_can::Error::kind(&e), ErrorKind::Crc);
    assert!(std::format!("{e}").starts_with("mock CAN bus: "));
    assert_eq!(MockError::from(ErrorKind::Bit).kind, ErrorKind::Bit);
}

#[test]
fn blocking_can_delivers_when_it_must_and_never_hangs() {
    let bus: Bus<3, 4> = Bus::new(1);
    bus.set_auto_deliver(false);
    bus.set_mailboxes(0, 1);
    let mut a = bus.endpoint(0).unwrap();
    let mut b = bus.endpoint(1).unwrap();
    let mut c = bus.endpoint(2).unwrap();
    assert_eq!(Can::transmit(&mut c, &ext(0x5)), Ok(None));
    assert_eq!(blocking::Can::transmit(&mut a, &ext(0x10)), Ok(()));
    // a's only mailbox is full: the bus runs (c's higher-priority frame first,
    // then a's) until a has room; no displacement.
    assert_eq!(blocking::Can::transmit(&mut a, &ext(0x20)), Ok(()));
    assert_eq!(bus.stats().displaced, 0);
    assert_eq!(bus.pending(), 1);
    assert_eq!(Can::receive(&mut b), Ok(ext(0x5)));
    assert_eq!(Can::receive(&mut b), Ok(ext(0x10)));
    assert_eq!(Can::receive(&mut b), Err(nb::Error::WouldBlock));
    // Blocking receive delivers the pending frame it is waiting for.
    assert_eq!(blocking::Can::receive(&mut b), Ok(ext(0x20)));
    assert_eq!(bus.pending(), 0);
    // Nothing pending, nothing queued: an error instead of blocking forever.
    assert_eq!(
        blocking::Can::receive(&mut b),
        Err(MockError::new(ErrorKind::Other))
    );
    // Pending frames that never reach this endpoint (its own) also end in Other.
    assert_eq!(Can::transmit(&mut b, &ext(0x30)), Ok(None));
    assert_eq!(
        blocking::Can::receive(&mut b),
        Err(MockError::new(ErrorKind::Other))
    );
    assert_eq!(bus.pending(), 0);
    assert_eq!(blocking::Can::receive(&mut c), Ok(ext(0x10)));
    // With auto-delivery, blocking transmit sends at once.
    bus.set_auto_deliver(true);
    assert_eq!(blocking::Can::transmit(&mut c, &ext(0x40)), Ok(()));
    assert_eq!(bus.pending(), 0);
}

#[test]
fn endpoints_are_taken_once() {
    let bus: Bus<2, 4> = Bus::new(1);
    {
        let a = bus.endpoint(0).unwrap();
        assert_eq!(std::format!("{a:?}"), "Endpoint { index: 0, .. }");
        assert_eq!(a.index(), 0);
        assert!(bus.endpoint(0).is_none());
        assert!(bus.endpoint(2).is_none());
    }
    assert!(bus.endpoint(0).is_none(), "not even after drop");
    assert_eq!(bus.endpoint(1).map(|e| e.index()), Some(1));
    assert!(bus.endpoint(1).is_none());
}
