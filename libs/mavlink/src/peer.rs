//! Which system on the link is the autopilot: heartbeats and telemetry are taken only from its
//! system and component id, and on a `udpin` link replies go only to the address it speaks from.
//!
//! Without this, anything that can send a datagram to the port steers the link: one garbage
//! datagram moved the reply address to a stranger, and a second system claiming to be an
//! autopilot was adopted once the real one fell silent.

use mavlink::MavHeader;

/// The autopilot's identity on the link.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct AutopilotId {
    /// System id (ArduPilot `SYSID_THISMAV`; the vehicle's, shared with its companion computer).
    pub system_id: u8,
    /// Component id (1 = `MAV_COMP_ID_AUTOPILOT1`); 0 accepts any component of the system.
    pub component_id: u8,
}

impl AutopilotId {
    /// True when a frame with `header` comes from the autopilot.
    pub fn sent(&self, header: &MavHeader) -> bool {
        u8::try_from(header.system_id).is_ok_and(|s| s == self.system_id)
            && (self.component_id == 0 || header.component_id == self.component_id)
    }
}

/// Where a `udpin` link replies: the first address a valid frame of the autopilot came from.
/// Datagrams without such a frame (garbage, other systems) never move it; a valid frame of the
/// autopilot from a new address does (the autopilot restarted on another port).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct PeerLock<A> {
    /// The reply address, once the autopilot was heard.
    pub peer: Option<A>,
    /// Datagrams from another address that did not carry a frame of the autopilot.
    pub refused: u64,
}

impl<A> Default for PeerLock<A> {
    fn default() -> Self {
        PeerLock {
            peer: None,
            refused: 0,
        }
    }
}

impl<A: PartialEq + Copy> PeerLock<A> {
    /// Notes a datagram from `from` whose frames have `headers`; `autopilot` `None` takes any
    /// valid frame (the link is not told whom to expect).
    pub fn observe<'a>(
        &mut self,
        from: A,
        headers: impl IntoIterator<Item = &'a MavHeader>,
        autopilot: Option<AutopilotId>,
    ) {
        let mut headers = headers.into_iter();
        let theirs = match autopilot {
            Some(id) => headers.any(|h| id.sent(h)),
            None => headers.next().is_some(),
        };
        if theirs {
            self.peer = Some(from);
        } else if self.peer != Some(from) {
            self.refused += 1;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn h(sys: u8, comp: u8) -> MavHeader {
        MavHeader {
            system_id: sys.into(),
            component_id: comp,
            sequence: 0,
        }
    }

    #[test]
    fn only_the_autopilot_sets_or_moves_the_reply_address() {
        let ap = Some(AutopilotId {
            system_id: 1,
            component_id: 1,
        });
        let mut lock = PeerLock::<u16>::default();
        lock.observe(9, &[], ap); // garbage
        lock.observe(8, &[h(99, 1)], ap); // another system
        lock.observe(7, &[h(1, 191)], ap); // the companion's component, not the autopilot
        assert_eq!(lock.peer, None);
        lock.observe(5, &[h(99, 1), h(1, 1)], ap);
        assert_eq!(lock.peer, Some(5));
        lock.observe(9, &[], ap);
        lock.observe(8, &[h(99, 1)], ap);
        assert_eq!((lock.peer, lock.refused), (Some(5), 5));
        lock.observe(6, &[h(1, 1)], ap);
        assert_eq!(lock.peer, Some(6));
        // Any component of the system when the component is 0.
        let any = AutopilotId {
            system_id: 1,
            component_id: 0,
        };
        assert!(any.sent(&h(1, 250)) && !any.sent(&h(2, 1)));
    }
}
