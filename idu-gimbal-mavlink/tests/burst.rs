//! Bursts of requests: no ACK promising a message that is then dropped, whatever the outbox
//! has room for; a request refused (`TEMPORARILY_REJECTED`) when its answer would not fit;
//! nothing lost uncounted.

mod common;
use common::*;

use idu_gimbal::link::Link;
use idu_gimbal::video::{Camera as VideoCamera, Family};
use idu_gimbal::wire::ids;
use idu_gimbal::wire::postback::{GimbalType, Postback};
use idu_gimbal_mavlink::camera::CameraConfig;
use idu_gimbal_mavlink::Bridge;
use mavio::dialects::common::enums::{MavCmd, MavResult};
use mavio::dialects::common::messages::CommandAck;
use proptest::prelude::*;

/// Requests that promise one message: (component, message id).
const REQUESTS: [(u8, u32); 5] = [(100, 259), (100, 260), (100, 261), (100, 262), (154, 283)];
/// The clients sending them.
const CLIENTS: [(u8, u8); 3] = [(255, 190), (255, 191), (1, 191)];

/// A camera bridge whose gimbal type is known (so CAMERA_INFORMATION is answered).
fn bridge() -> Bridge<Link> {
    let mut b =
        camera_bridge(CameraConfig::with_streams_of(&VideoCamera::new(Family::X3)).unwrap());
    let p = Postback {
        gimbal_type: GimbalType::X30,
        ..Postback::default()
    };
    for data in p.to_can_frames() {
        b.gimbal_mut().receive(ids::POSTBACK, &data, t(1));
    }
    b.poll(t(1));
    let _ = sent(&mut b);
    b
}

fn request(client: usize, seq: u8, which: usize) -> Vec<u8> {
    let (component, id) = REQUESTS[which];
    frame(
        CLIENTS[client],
        seq,
        &command((AP.0, component), MavCmd::RequestMessage, id as f32, 0.0),
    )
}

/// What came out: per client, the results of its ACKs in order; per message id, how many.
#[derive(Default, Debug)]
struct Answers {
    acks: Vec<Vec<MavResult>>,
    messages: std::collections::HashMap<u32, usize>,
}

impl Answers {
    fn take(&mut self, b: &mut Bridge<Link>) {
        if self.acks.is_empty() {
            self.acks = vec![Vec::new(); CLIENTS.len()];
        }
        for f in sent(b) {
            if f.message_id() == 77 {
                let ack: CommandAck = f.decode_message().unwrap();
                let c = CLIENTS
                    .iter()
                    .position(|&c| c == (ack.target_system, ack.target_component))
                    .unwrap();
                self.acks[c].push(ack.result);
            } else {
                *self.messages.entry(f.message_id()).or_default() += 1;
            }
        }
    }
}

#[test]
fn six_information_requests_in_one_chunk_each_get_one_answer_and_none_a_false_promise() {
    // Six REQUEST_MESSAGE(CAMERA_INFORMATION) in one datagram once got six ACCEPTED and
    // three messages.
    let mut b = bridge();
    let burst: Vec<u8> = (0..6).flat_map(|i| request(0, i, 0)).collect();
    b.receive(&burst, t(10));
    let mut a = Answers::default();
    a.take(&mut b);
    assert_eq!(a.acks[0].len(), 6, "{a:?}");
    let accepted = a.acks[0]
        .iter()
        .filter(|&&r| r == MavResult::Accepted)
        .count();
    assert_eq!(
        a.messages.get(&259).copied().unwrap_or(0),
        accepted,
        "{a:?}"
    );
    assert!(accepted >= 1, "{a:?}");
    let rejected = a.acks[0]
        .iter()
        .filter(|&&r| r == MavResult::TemporarilyRejected)
        .count();
    assert_eq!(accepted + rejected, 6, "{a:?}");
    assert_eq!(b.stats().rejected_no_room as usize, rejected);
    // The outbox drained, the same burst is answered as far as room goes again.
    b.receive(&burst, t(20));
    let mut again = Answers::default();
    again.take(&mut b);
    assert_eq!(again.acks[0].len(), 6);
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]

    /// Any interleaving of requests from three clients, fed in any split, the outbox drained
    /// at any points: every ACCEPTED gets its message, no request two ACKs, and a request
    /// left without one only when not even its refusal fitted the outbox, counted.
    #[test]
    fn no_promise_is_dropped_and_nothing_is_lost_uncounted(
        requests in prop::collection::vec((0..CLIENTS.len(), 0..REQUESTS.len()), 1..40),
        cuts in prop::collection::vec((1usize..400, any::<bool>()), 1..40),
    ) {
        let mut b = bridge();
        let mut bytes = Vec::new();
        let mut asked = vec![0usize; CLIENTS.len()];
        for (i, &(client, which)) in requests.iter().enumerate() {
            bytes.extend(request(client, i as u8, which));
            asked[client] += 1;
        }
        let mut a = Answers::default();
        let mut at = 0;
        for (ms, &(len, drain)) in (10..).zip(cuts.iter().cycle()) {
            if at >= bytes.len() {
                break;
            }
            let end = (at + len).min(bytes.len());
            b.receive(&bytes[at..end], t(ms));
            at = end;
            if drain {
                a.take(&mut b);
            }
        }
        a.take(&mut b);
        let mut unanswered = 0;
        for (c, &n) in asked.iter().enumerate() {
            prop_assert!(a.acks[c].len() <= n, "client {}: {:?}", c, a);
            unanswered += n - a.acks[c].len();
        }
        let accepted: usize = a.acks.iter().flatten().filter(|&&r| r == MavResult::Accepted).count();
        let messages: usize = REQUESTS.iter().map(|(_, id)| a.messages.get(id).copied().unwrap_or(0)).sum();
        prop_assert_eq!(messages, accepted, "{:?}", a);
        prop_assert!(a.acks.iter().flatten().all(|r| matches!(r, MavResult::Accepted | MavResult::TemporarilyRejected)));
        // Only refusals are ever dropped, each counted; with a drain after every ~20
        // requests (1 KiB of outbox), none is.
        prop_assert_eq!(b.stats().outbox_full as usize, unanswered, "{:?}", b.stats());
    }
}
