//! Stereo pairs made from four topics (left and right images, left and
//! right camera infos) by their header stamps, without reading pixels.
//!
//! A pair is a left image, the right image whose stamp is nearest to it
//! within the tolerance, and the camera info of each, stamped as its image
//! within the tolerance. The tolerance is 0 by default (exact stamps, what
//! a hardware-synchronised stereo driver gives); a positive one pairs as
//! message_filters' `ApproximateTime` does with `max_interval_duration`,
//! by the nearest stamp rather than its full search. Each topic keeps at
//! most `history_depth` messages waiting for their partners.
//!
//! What cannot be paired is counted, never an error:
//! * a message older than the last pair made (out of order) is dropped;
//! * an image or info left behind by a newer pair, or pushed out of a full
//!   queue, had no partner (one half missing);
//! * a set whose camera info does not describe its image (other width or
//!   height) is dropped.

use std::collections::VecDeque;

/// One of the four streams a pair is made from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Part {
    /// The left image.
    LeftImage,
    /// The right image.
    RightImage,
    /// The left camera's info.
    LeftInfo,
    /// The right camera's info.
    RightInfo,
}

impl Part {
    /// The four, in the order a pair lists them.
    pub const ALL: [Self; 4] = [
        Self::LeftImage,
        Self::RightImage,
        Self::LeftInfo,
        Self::RightInfo,
    ];

    /// Whether it is an image (not a camera info).
    pub fn is_image(self) -> bool {
        matches!(self, Self::LeftImage | Self::RightImage)
    }

    fn index(self) -> usize {
        match self {
            Self::LeftImage => 0,
            Self::RightImage => 1,
            Self::LeftInfo => 2,
            Self::RightInfo => 3,
        }
    }
}

/// What the pairing reads of a message: its header stamp and the image
/// size it has (an image) or describes (a camera info).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PartHeader {
    /// The header stamp (ns).
    pub stamp_ns: i64,
    /// Width (px).
    pub width: u32,
    /// Height (px).
    pub height: u32,
}

/// How pairs are matched.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PairingSettings {
    /// Largest stamp difference within a pair (ns; 0: exact stamps).
    pub tolerance_ns: i64,
    /// Messages kept per topic while they wait for their partners
    /// (default 10: 4 s of a 2.5 fps stream).
    pub history_depth: usize,
}

impl Default for PairingSettings {
    fn default() -> Self {
        Self {
            tolerance_ns: 0,
            history_depth: 10,
        }
    }
}

/// A matched stereo pair, its messages as received.
#[derive(Debug, Clone, PartialEq)]
pub struct StereoPair<T> {
    /// The left image's stamp (ns): the pair's.
    pub stamp_ns: i64,
    /// The left image.
    pub left: T,
    /// The right image.
    pub right: T,
    /// The left camera's info.
    pub left_info: T,
    /// The right camera's info.
    pub right_info: T,
}

/// Messages that made no pair, by why.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct PairingFaults {
    /// Images that never had a partner (the other image or either info
    /// missing).
    pub unpaired_images: u64,
    /// Camera infos that never had an image.
    pub unpaired_infos: u64,
    /// Messages stamped at or before the last pair made.
    pub out_of_order: u64,
    /// Sets whose camera info describes another image size.
    pub info_mismatch: u64,
}

/// Makes stereo pairs from the four streams.
#[derive(Debug, Clone)]
pub struct StereoPairer<T> {
    settings: PairingSettings,
    queues: [VecDeque<(PartHeader, T)>; 4],
    last_pair_ns: Option<i64>,
    faults: PairingFaults,
}

impl<T> StereoPairer<T> {
    /// A pairer with nothing waiting.
    pub fn new(settings: PairingSettings) -> Self {
        Self {
            settings: PairingSettings {
                tolerance_ns: settings.tolerance_ns.max(0),
                history_depth: settings.history_depth.max(1),
            },
            queues: Default::default(),
            last_pair_ns: None,
            faults: PairingFaults::default(),
        }
    }

    /// How it pairs (the tolerance and depth as clamped).
    pub fn settings(&self) -> PairingSettings {
        self.settings
    }

    /// What made no pair so far.
    pub fn faults(&self) -> PairingFaults {
        self.faults
    }

    /// Takes one message; returns the pair it completes, if any.
    pub fn push(&mut self, part: Part, header: PartHeader, message: T) -> Option<StereoPair<T>> {
        if self
            .last_pair_ns
            .is_some_and(|last| header.stamp_ns <= last)
        {
            self.faults.out_of_order += 1;
            return None;
        }
        let queue = &mut self.queues[part.index()];
        let at = queue.partition_point(|(h, _)| h.stamp_ns <= header.stamp_ns);
        queue.insert(at, (header, message));
        if queue.len() > self.settings.history_depth {
            queue.pop_front();
            self.count_unpaired(part, 1);
        }
        self.try_pair()
    }

    fn count_unpaired(&mut self, part: Part, n: u64) {
        match part {
            Part::LeftImage | Part::RightImage => self.faults.unpaired_images += n,
            Part::LeftInfo | Part::RightInfo => self.faults.unpaired_infos += n,
        }
    }

    /// The index in `part`'s queue of the message nearest `stamp_ns`
    /// within the tolerance.
    fn nearest(&self, part: Part, stamp_ns: i64) -> Option<usize> {
        let tolerance = self.settings.tolerance_ns;
        self.queues[part.index()]
            .iter()
            .enumerate()
            .map(|(i, (h, _))| (i, (h.stamp_ns - stamp_ns).abs()))
            .filter(|&(_, d)| d <= tolerance)
            .min_by_key(|&(_, d)| d)
            .map(|(i, _)| i)
    }

    /// Pairs the oldest left image that has every partner.
    fn try_pair(&mut self) -> Option<StereoPair<T>> {
        let lefts: Vec<i64> = self.queues[0].iter().map(|(h, _)| h.stamp_ns).collect();
        for (l, stamp) in lefts.into_iter().enumerate() {
            let Some(r) = self.nearest(Part::RightImage, stamp) else {
                continue;
            };
            let right_stamp = self.queues[1][r].0.stamp_ns;
            let (Some(li), Some(ri)) = (
                self.nearest(Part::LeftInfo, stamp),
                self.nearest(Part::RightInfo, right_stamp),
            ) else {
                continue;
            };
            return self.take(stamp, [l, r, li, ri]);
        }
        None
    }

    /// Takes the set at `indices`, drops what is older, and checks the
    /// infos against their images.
    fn take(&mut self, stamp_ns: i64, indices: [usize; 4]) -> Option<StereoPair<T>> {
        let mut taken = Vec::with_capacity(4);
        for (q, &i) in indices.iter().enumerate() {
            let item = self.queues[q].remove(i)?;
            taken.push(item);
        }
        self.last_pair_ns = Some(stamp_ns);
        for (q, part) in [
            Part::LeftImage,
            Part::RightImage,
            Part::LeftInfo,
            Part::RightInfo,
        ]
        .into_iter()
        .enumerate()
        {
            let before = self.queues[q].len();
            self.queues[q].retain(|(h, _)| h.stamp_ns > stamp_ns);
            self.count_unpaired(part, (before - self.queues[q].len()) as u64);
        }
        let mut taken = taken.into_iter();
        let (Some(left), Some(right), Some(left_info), Some(right_info)) =
            (taken.next(), taken.next(), taken.next(), taken.next())
        else {
            return None;
        };
        let size = |h: &PartHeader| (h.width, h.height);
        if size(&left.0) != size(&left_info.0) || size(&right.0) != size(&right_info.0) {
            self.faults.info_mismatch += 1;
            return None;
        }
        Some(StereoPair {
            stamp_ns,
            left: left.1,
            right: right.1,
            left_info: left_info.1,
            right_info: right_info.1,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn header(stamp_ns: i64) -> PartHeader {
        PartHeader {
            stamp_ns,
            width: 512,
            height: 384,
        }
    }

    /// Pushes the four parts of a pair at `stamp` (right `skew` ns later),
    /// in `order`, each message its part's index and stamp.
    fn push_set(
        p: &mut StereoPairer<(usize, i64)>,
        stamp: i64,
        skew: i64,
        order: [Part; 4],
    ) -> Vec<StereoPair<(usize, i64)>> {
        order
            .into_iter()
            .filter_map(|part| {
                let s = match part {
                    Part::RightImage | Part::RightInfo => stamp + skew,
                    Part::LeftImage | Part::LeftInfo => stamp,
                };
                p.push(part, header(s), (part.index(), s))
            })
            .collect()
    }

    const IN_ORDER: [Part; 4] = [
        Part::LeftImage,
        Part::RightImage,
        Part::LeftInfo,
        Part::RightInfo,
    ];
    const SHUFFLED: [Part; 4] = [
        Part::RightInfo,
        Part::LeftImage,
        Part::LeftInfo,
        Part::RightImage,
    ];

    #[test]
    fn exact_stamps_pair_whatever_order_the_parts_arrive_in() {
        let mut p = StereoPairer::new(PairingSettings::default());
        for (k, order) in [IN_ORDER, SHUFFLED, IN_ORDER].into_iter().enumerate() {
            let stamp = 400_000_000 * k as i64;
            let pairs = push_set(&mut p, stamp, 0, order);
            assert_eq!(pairs.len(), 1, "set {k}");
            let pair = &pairs[0];
            assert_eq!(pair.stamp_ns, stamp);
            assert_eq!(
                [pair.left, pair.right, pair.left_info, pair.right_info],
                [(0, stamp), (1, stamp), (2, stamp), (3, stamp)]
            );
        }
        assert_eq!(p.faults(), PairingFaults::default());
    }

    #[test]
    fn a_skew_pairs_only_within_the_tolerance() {
        let mut exact = StereoPairer::new(PairingSettings::default());
        assert!(push_set(&mut exact, 0, 2_000_000, IN_ORDER).is_empty());
        let mut loose = StereoPairer::new(PairingSettings {
            tolerance_ns: 5_000_000,
            ..PairingSettings::default()
        });
        let pairs = push_set(&mut loose, 0, 2_000_000, IN_ORDER);
        assert_eq!(pairs.len(), 1);
        assert_eq!(pairs[0].right, (1, 2_000_000));
        assert_eq!(pairs[0].right_info, (3, 2_000_000));
    }

    #[test]
    fn a_missing_half_is_counted_when_a_newer_pair_passes_it() {
        let mut p = StereoPairer::new(PairingSettings::default());
        // Set 0 loses its right image; set 1 is whole.
        for part in [Part::LeftImage, Part::LeftInfo, Part::RightInfo] {
            assert!(p.push(part, header(0), (part.index(), 0)).is_none());
        }
        assert_eq!(push_set(&mut p, 400, 0, IN_ORDER).len(), 1);
        let f = p.faults();
        assert_eq!((f.unpaired_images, f.unpaired_infos), (1, 2));
        // The late right image of set 0 is out of order now.
        assert!(p.push(Part::RightImage, header(0), (1, 0)).is_none());
        assert_eq!(p.faults().out_of_order, 1);
    }

    #[test]
    fn a_full_queue_drops_its_oldest() {
        let mut p = StereoPairer::new(PairingSettings {
            tolerance_ns: 0,
            history_depth: 3,
        });
        for k in 0..5 {
            assert!(p.push(Part::LeftImage, header(k), (0, k)).is_none());
        }
        assert_eq!(p.faults().unpaired_images, 2);
    }

    #[test]
    fn an_info_of_another_size_drops_the_set() {
        let mut p = StereoPairer::new(PairingSettings::default());
        p.push(Part::LeftImage, header(0), 0);
        p.push(Part::RightImage, header(0), 1);
        p.push(Part::RightInfo, header(0), 3);
        let wrong = PartHeader {
            width: 1024,
            ..header(0)
        };
        assert!(p.push(Part::LeftInfo, wrong, 2).is_none());
        assert_eq!(p.faults().info_mismatch, 1);
        // The next set pairs.
        for (i, part) in IN_ORDER.into_iter().enumerate() {
            let pair = p.push(part, header(400), i);
            assert_eq!(pair.is_some(), i == 3);
        }
    }
}
