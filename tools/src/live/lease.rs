//! Holds that keep their word: a lease per holder, as SPEC §18's lease is per master. The
//! firmware ends a hold 10 s after its master's last frame, but `utile live` polls without
//! end, so it keeps the same promise for its own holders:
//!
//! - a **page** (one that follows the events, `GET /api/events?page=ID`, and names itself in
//!   its scan requests) holds while it follows them, and 10 s after it closed;
//! - **the API** (a script: a scan request without a page that follows) holds 10 s past its
//!   last scan request (`hold`, `step`): a script renews by asking again;
//! - **Run** ends every holder's hold at once.
//!
//! When the last holder's lease has run out the line sends Run (holding register 32 = 0), and
//! sends it again every [`RUN_AGAIN`] until the uTile answers it or a snapshot shows it
//! running freely. The line's thread records a hold before the write goes (an answer lost
//! on the way does not lose the record: the write may have landed), and learns every
//! write's outcome; holds made by other masters through the gateway are theirs.
//!
//! Plain structs that take `now` and do no I/O: the line's thread owns [`Leases`], the events
//! route keeps [`Pages`] (a `watch` the line reads).

use std::collections::BTreeMap;
use std::time::{Duration, Instant};

/// A holder's hold lives this long past its last sign of life (SPEC §18's lease).
pub const LEASE: Duration = Duration::from_secs(10);
/// A Run that got no answer is sent again after this.
pub const RUN_AGAIN: Duration = Duration::from_secs(1);
/// At most this many pages are known at once (following, or closed lately).
pub const MAX_PAGES: usize = 256;
/// A page closed this long ago is forgotten (its holds ended long before).
const FORGET: Duration = Duration::from_secs(60);
/// The longest page name.
const MAX_PAGE_NAME: usize = 64;

/// A page's name for itself: 1..64 letters, digits, `-` or `_` (the page makes it at random).
#[derive(Clone, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct PageId(String);

/// A page name that cannot be one.
#[derive(Debug, thiserror::Error)]
#[error("{0:?} is no page name: 1..{MAX_PAGE_NAME} letters, digits, '-' or '_'")]
pub struct BadPage(pub String);

impl PageId {
    /// `name` as a page's name.
    pub fn parse(name: &str) -> Result<PageId, BadPage> {
        let ok = (1..=MAX_PAGE_NAME).contains(&name.len())
            && name
                .bytes()
                .all(|b| b.is_ascii_alphanumeric() || b == b'-' || b == b'_');
        if ok {
            Ok(PageId(name.to_string()))
        } else {
            Err(BadPage(name.to_string()))
        }
    }
}

/// Who holds a uTile's scan.
#[derive(Clone, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Holder {
    /// A page that follows the events.
    Page(PageId),
    /// A script through the API (any scan request not from a page that follows).
    Api,
}

/// Too many pages follow the events.
#[derive(Debug, thiserror::Error)]
#[error("{MAX_PAGES} pages follow the events already: close one and load this page again")]
pub struct TooManyPages;

/// One page's streams of events.
#[derive(Clone, Copy, Debug)]
struct Follow {
    /// Streams open now.
    streams: u32,
    /// When its last stream closed (while `streams` is 0).
    closed: Instant,
}

/// The pages that follow the events, and those that did within the last minute.
#[derive(Clone, Debug, Default)]
pub struct Pages {
    pages: BTreeMap<PageId, Follow>,
}

impl Pages {
    /// Page `id` opened a stream of events at `now`.
    pub fn opened(&mut self, id: &PageId, now: Instant) -> Result<(), TooManyPages> {
        self.forget(now);
        if let Some(f) = self.pages.get_mut(id) {
            f.streams += 1;
            return Ok(());
        }
        if self.pages.len() >= MAX_PAGES {
            return Err(TooManyPages);
        }
        self.pages.insert(
            id.clone(),
            Follow {
                streams: 1,
                closed: now,
            },
        );
        Ok(())
    }

    /// One of page `id`'s streams closed at `now`.
    pub fn closed(&mut self, id: &PageId, now: Instant) {
        if let Some(f) = self.pages.get_mut(id) {
            f.streams = f.streams.saturating_sub(1);
            if f.streams == 0 {
                f.closed = now;
            }
        }
        self.forget(now);
    }

    /// The last moment page `id` followed the events (`now` while it does); `None` for a
    /// page that never did, or was forgotten.
    pub fn seen(&self, id: &PageId, now: Instant) -> Option<Instant> {
        self.pages
            .get(id)
            .map(|f| if f.streams > 0 { now } else { f.closed })
    }

    /// Whether page `id` is known (follows, or did lately).
    pub fn knows(&self, id: &PageId) -> bool {
        self.pages.contains_key(id)
    }

    /// Pages following now.
    pub fn following(&self) -> usize {
        self.pages.values().filter(|f| f.streams > 0).count()
    }

    fn forget(&mut self, now: Instant) {
        self.pages
            .retain(|_, f| f.streams > 0 || now.saturating_duration_since(f.closed) < FORGET);
    }
}

/// One uTile's hold as `utile live` keeps it.
#[derive(Clone, Debug)]
enum Hold {
    /// Held: each holder and its last scan request.
    Held(BTreeMap<Holder, Instant>),
    /// Every lease ran out (or Run was asked for) at `decided`: Run goes (again) at `next`
    /// until it is answered or a snapshot shows the scan running freely.
    Releasing { decided: Instant, next: Instant },
}

/// Every uTile held through `utile live`, and who holds it until when.
#[derive(Clone, Debug, Default)]
pub struct Leases {
    units: BTreeMap<u8, Hold>,
}

impl Leases {
    /// A hold or a step of uTile `addr` by `holder` goes on the line at `now`: recorded
    /// before the write goes, so a lost answer does not lose it.
    pub fn asked(&mut self, addr: u8, holder: Holder, now: Instant) {
        match self.units.get_mut(&addr) {
            Some(Hold::Held(holders)) => {
                holders.insert(holder, now);
            }
            _ => {
                self.units
                    .insert(addr, Hold::Held(BTreeMap::from([(holder, now)])));
            }
        }
    }

    /// uTile `addr` refused `holder`'s hold or step (an exception): it holds nothing by it.
    pub fn refused(&mut self, addr: u8, holder: &Holder) {
        if let Some(Hold::Held(holders)) = self.units.get_mut(&addr) {
            holders.remove(holder);
            if holders.is_empty() {
                self.units.remove(&addr);
            }
        }
    }

    /// A Run of uTile `addr` goes on the line at `now` (a page's, the API's): every holder's
    /// hold ends; until the Run is answered the uTile is being released.
    pub fn run(&mut self, addr: u8, now: Instant) {
        self.units.insert(
            addr,
            Hold::Releasing {
                decided: now,
                next: now + RUN_AGAIN,
            },
        );
    }

    /// uTile `addr` answered a Run (anyone's): it runs freely, nothing more to do.
    pub fn ran(&mut self, addr: u8) {
        self.units.remove(&addr);
    }

    /// A Run of uTile `addr` got no answer at `now`: it goes again after [`RUN_AGAIN`].
    pub fn run_missed(&mut self, addr: u8, now: Instant) {
        if let Some(Hold::Releasing { next, .. }) = self.units.get_mut(&addr) {
            *next = now + RUN_AGAIN;
        }
    }

    /// A snapshot of uTile `addr` read at `at` shows its scan running freely: a release
    /// decided before it is done (the Run landed though its answer was lost, or the
    /// firmware's own lease ended the hold).
    pub fn runs_freely(&mut self, addr: u8, at: Instant) {
        if let Some(Hold::Releasing { decided, .. }) = self.units.get(&addr) {
            if at > *decided {
                self.units.remove(&addr);
            }
        }
    }

    /// The uTile to send Run to at `now`, if any: one whose last holder's lease has run out,
    /// or whose Run goes again. The caller sends it and says how it went ([`Leases::ran`],
    /// [`Leases::run_missed`]).
    pub fn due(&mut self, now: Instant, pages: &Pages) -> Option<u8> {
        for (&addr, hold) in self.units.iter_mut() {
            if let Hold::Held(holders) = hold {
                holders.retain(|h, last| now < Self::ends(h, *last, now, pages));
                if holders.is_empty() {
                    *hold = Hold::Releasing {
                        decided: now,
                        next: now,
                    };
                }
            }
            if let Hold::Releasing { next, .. } = hold {
                if *next <= now {
                    *next = now + RUN_AGAIN;
                    return Some(addr);
                }
            }
        }
        None
    }

    /// When `holder`'s hold, last asked for at `last`, ends: [`LEASE`] past the later of
    /// that request and the last moment its page followed the events.
    fn ends(holder: &Holder, last: Instant, now: Instant, pages: &Pages) -> Instant {
        let alive = match holder {
            Holder::Page(id) => pages.seen(id, now).map_or(last, |seen| seen.max(last)),
            Holder::Api => last,
        };
        alive + LEASE
    }

    /// Whether uTile `addr` is held or being released through `utile live`.
    pub fn holds(&self, addr: u8) -> bool {
        self.units.contains_key(&addr)
    }

    /// Nothing held, nothing to release.
    pub fn is_empty(&self) -> bool {
        self.units.is_empty()
    }
}

#[cfg(test)]
mod tests {
    //! On tokio's paused clock: the time moves only when a test advances it, by the
    //! millisecond, and nothing sleeps.

    use super::*;
    use tokio::time::advance;

    /// The paused clock's now.
    fn now() -> Instant {
        tokio::time::Instant::now().into_std()
    }

    async fn after_ms(ms: u64) {
        advance(Duration::from_millis(ms)).await;
    }

    fn page(name: &str) -> PageId {
        PageId::parse(name).unwrap()
    }

    #[tokio::test(start_paused = true)]
    async fn an_api_hold_lives_10_s_past_its_last_request_and_a_script_renews_it() {
        let (mut leases, pages) = (Leases::default(), Pages::default());
        leases.asked(1, Holder::Api, now());
        after_ms(9_000).await;
        assert_eq!(leases.due(now(), &pages), None);
        // The script asks again (a step): 10 s from here.
        leases.asked(1, Holder::Api, now());
        after_ms(9_999).await;
        assert_eq!(
            leases.due(now(), &pages),
            None,
            "held 19.999 s after the first"
        );
        after_ms(1).await;
        assert_eq!(
            leases.due(now(), &pages),
            Some(1),
            "10 s after the last request"
        );
        assert_eq!(leases.due(now(), &pages), None, "one Run at a time");
        leases.ran(1);
        after_ms(60_000).await;
        assert_eq!(leases.due(now(), &pages), None);
        assert!(leases.is_empty());
    }

    #[tokio::test(start_paused = true)]
    async fn a_pages_hold_lives_while_it_follows_and_10_s_after_it_closed() {
        let (mut leases, mut pages) = (Leases::default(), Pages::default());
        let p = page("a1");
        pages.opened(&p, now()).unwrap();
        leases.asked(2, Holder::Page(p.clone()), now());
        // An hour with the page open: held.
        for _ in 0..3_600 {
            after_ms(1_000).await;
            assert_eq!(leases.due(now(), &pages), None);
        }
        // A second stream of the same page (the browser reconnected) closes: still open.
        pages.opened(&p, now()).unwrap();
        pages.closed(&p, now());
        after_ms(20_000).await;
        assert_eq!(leases.due(now(), &pages), None);
        pages.closed(&p, now());
        assert_eq!(pages.following(), 0);
        after_ms(9_999).await;
        assert_eq!(leases.due(now(), &pages), None, "9.999 s after it closed");
        after_ms(1).await;
        assert_eq!(leases.due(now(), &pages), Some(2), "10 s after it closed");
    }

    #[tokio::test(start_paused = true)]
    async fn each_holder_has_its_own_lease_and_the_last_one_decides() {
        let (mut leases, mut pages) = (Leases::default(), Pages::default());
        let p = page("b2");
        pages.opened(&p, now()).unwrap();
        leases.asked(1, Holder::Page(p.clone()), now());
        after_ms(5_000).await;
        leases.asked(1, Holder::Api, now());
        pages.closed(&p, now());
        // The page's lease and the script's both end 10 s from here.
        after_ms(8_000).await;
        leases.asked(1, Holder::Api, now());
        after_ms(2_000).await;
        assert_eq!(leases.due(now(), &pages), None, "the script renewed");
        after_ms(7_999).await;
        assert_eq!(leases.due(now(), &pages), None);
        after_ms(1).await;
        assert_eq!(leases.due(now(), &pages), Some(1));
    }

    #[tokio::test(start_paused = true)]
    async fn run_ends_every_hold_and_a_run_that_gets_no_answer_goes_again() {
        let (mut leases, mut pages) = (Leases::default(), Pages::default());
        let p = page("c3");
        pages.opened(&p, now()).unwrap();
        leases.asked(3, Holder::Page(p), now());
        leases.asked(3, Holder::Api, now());
        after_ms(100).await;
        // The page's Run goes now: no other Run while it is on the line.
        leases.run(3, now());
        assert_eq!(leases.due(now(), &pages), None);
        after_ms(400).await;
        leases.run_missed(3, now());
        after_ms(999).await;
        assert_eq!(leases.due(now(), &pages), None);
        after_ms(1).await;
        assert_eq!(leases.due(now(), &pages), Some(3), "sent again 1 s after");
        after_ms(300).await;
        leases.run_missed(3, now());
        after_ms(1_000).await;
        assert_eq!(leases.due(now(), &pages), Some(3), "and again");
        leases.ran(3);
        after_ms(10_000).await;
        assert_eq!(leases.due(now(), &pages), None, "answered: done");
        assert!(!leases.holds(3));
    }

    #[tokio::test(start_paused = true)]
    async fn a_snapshot_running_freely_after_the_release_ends_it() {
        let (mut leases, pages) = (Leases::default(), Pages::default());
        leases.asked(4, Holder::Api, now());
        let before = now();
        after_ms(10_000).await;
        assert_eq!(leases.due(now(), &pages), Some(4));
        // A snapshot read before the release proves nothing; one after it does.
        leases.runs_freely(4, before);
        assert!(leases.holds(4));
        after_ms(50).await;
        leases.runs_freely(4, now());
        assert!(!leases.holds(4));
        // While held, a snapshot running freely (steps under way) ends nothing.
        leases.asked(4, Holder::Api, now());
        after_ms(50).await;
        leases.runs_freely(4, now());
        assert!(leases.holds(4));
    }

    #[tokio::test(start_paused = true)]
    async fn a_refused_hold_holds_nothing_and_a_new_hold_stops_a_release() {
        let (mut leases, pages) = (Leases::default(), Pages::default());
        leases.asked(5, Holder::Api, now());
        leases.refused(5, &Holder::Api);
        assert!(leases.is_empty());
        leases.asked(5, Holder::Api, now());
        after_ms(10_000).await;
        assert_eq!(leases.due(now(), &pages), Some(5));
        leases.run_missed(5, now());
        leases.asked(5, Holder::Api, now());
        after_ms(5_000).await;
        assert_eq!(leases.due(now(), &pages), None, "held again: no Run");
    }

    #[tokio::test(start_paused = true)]
    async fn pages_are_bounded_and_forgotten_a_minute_after_they_closed() {
        let mut pages = Pages::default();
        for i in 0..MAX_PAGES {
            pages.opened(&page(&format!("p{i}")), now()).unwrap();
        }
        assert!(pages.opened(&page("one-more"), now()).is_err());
        pages.opened(&page("p0"), now()).unwrap();
        for i in 0..MAX_PAGES {
            pages.closed(&page(&format!("p{i}")), now());
        }
        assert!(pages.knows(&page("p1")) && pages.knows(&page("p0")));
        pages.closed(&page("p0"), now());
        after_ms(59_999).await;
        assert!(pages.opened(&page("one-more"), now()).is_err());
        after_ms(1).await;
        pages.opened(&page("one-more"), now()).unwrap();
        assert!(!pages.knows(&page("p1")));
        assert_eq!(pages.following(), 1);
    }

    #[test]
    fn a_page_name_is_short_and_plain() {
        assert!(PageId::parse("f3a9-0_Z").is_ok());
        assert!(PageId::parse("").is_err());
        assert!(PageId::parse(&"a".repeat(65)).is_err());
        assert!(PageId::parse("a b").is_err());
        assert!(PageId::parse("é").is_err());
    }
}
