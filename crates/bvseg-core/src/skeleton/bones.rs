//! Which bone each part moves with.
//!
//! Every sample casts votes for bones, and a part is bound to the bone with the most votes
//! of its samples (the first on ties). With a skin, a sample votes with the skin weights of
//! the triangles it holds (see [`crate::enclosure`]): a part then moves with the bone that
//! moves most of its surface, which keeps its volume small in every pose. Every sample also
//! casts a small vote for the bone of its nearest link, which alone decides for parts
//! without triangles and for skeletons without a skin; for a part the skeleton seeded, that
//! is the link that seeded it.
use super::{nearest, Link};
use crate::enclosure::Enclosure;
use crate::partition::Solid;
use crate::{Mesh, Skin};

/// The nearest link's vote, against a triangle's 1: it only breaks the silence of samples
/// without triangles.
const LINK_VOTE: f64 = 1e-3;

/// Each sample's votes, as lists of `(bone, weight)` in CSR form.
#[derive(Debug, Clone)]
pub struct Votes {
    offsets: Vec<u32>,
    votes: Vec<(u32, f64)>,
    bones: usize,
}

impl Votes {
    /// The votes of `solid`'s samples for the bones of `links` (and of `skin`'s joints, of
    /// which there are `bones`), through the triangles `enclosure` gives each sample.
    pub fn new(
        mesh: &Mesh,
        solid: &Solid,
        enclosure: &Enclosure,
        links: &[Link],
        skin: Option<&Skin>,
        bones: usize,
    ) -> Self {
        let n = solid.len();
        let mut per: Vec<Vec<(u32, f64)>> = crate::parallel::map(&solid.q, |&q| {
            if links.is_empty() {
                Vec::new()
            } else {
                vec![(links[nearest(links, q)].bone as u32, LINK_VOTE)]
            }
        });
        if let Some(skin) = skin {
            for (t, &s) in enclosure.triangle_sample.iter().enumerate() {
                for &v in &mesh.triangles()[t] {
                    for &(j, w) in &skin.weights[v as usize] {
                        if w > 0.0 {
                            per[s as usize].push((j, f64::from(w) / 3.0));
                        }
                    }
                }
            }
        }
        let mut offsets = Vec::with_capacity(n + 1);
        offsets.push(0u32);
        let mut votes: Vec<(u32, f64)> = Vec::new();
        for mut list in per {
            // A stable sort: equal bones' weights are summed in a fixed order, so the sums
            // have the same bits on any thread count.
            list.sort_by_key(|v| v.0);
            let start = votes.len();
            for (j, w) in list {
                let last = votes.len().wrapping_sub(1);
                if votes.len() > start && votes[last].0 == j {
                    votes[last].1 += w;
                } else {
                    votes.push((j, w));
                }
            }
            offsets.push(votes.len() as u32);
        }
        Self {
            offsets,
            votes,
            bones,
        }
    }

    /// The bone of each of the `k` parts of `labels`; `None` for a part without votes (only
    /// without links and skin).
    pub fn bones(&self, labels: &[u32], k: usize) -> Vec<Option<usize>> {
        if self.bones == 0 {
            return vec![None; k];
        }
        let mut tally = vec![0.0f64; k * self.bones];
        for (s, &l) in labels.iter().enumerate() {
            let (a, b) = (self.offsets[s] as usize, self.offsets[s + 1] as usize);
            for &(j, w) in &self.votes[a..b] {
                tally[l as usize * self.bones + j as usize] += w;
            }
        }
        tally
            .chunks(self.bones)
            .map(|t| {
                let mut best: Option<(f64, usize)> = None;
                for (j, &w) in t.iter().enumerate() {
                    if w > 0.0 && best.is_none_or(|(bw, _)| w > bw) {
                        best = Some((w, j));
                    }
                }
                best.map(|b| b.1)
            })
            .collect()
    }

    /// Each sample's bone by its skin votes alone: the bone with most weight among the
    /// triangles it holds, `None` for a sample that holds none.
    pub fn skin_bones(&self) -> Vec<Option<usize>> {
        (0..self.offsets.len() - 1)
            .map(|s| {
                let (a, b) = (self.offsets[s] as usize, self.offsets[s + 1] as usize);
                let mut best: Option<(f64, usize)> = None;
                for &(j, w) in &self.votes[a..b] {
                    if w > LINK_VOTE && best.is_none_or(|(bw, _)| w > bw) {
                        best = Some((w, j as usize));
                    }
                }
                best.map(|b| b.1)
            })
            .collect()
    }
}
