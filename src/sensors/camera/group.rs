//! Grouping of items by a `u32` key in linear time: the edge pixels' samples of a band by primitive, so that
//! shading fills its lanes with samples of one primitive. A counting sort over dense group numbers (given in
//! order of first appearance by a small open-addressing table) instead of a comparison sort of
//! `(key, index)` pairs: each group lists its items in increasing index order, as the sort did, and only the
//! order of the groups differs (which the shading of a group does not depend on).

/// Reusable buffers for [`Grouper::group`] (a band groups its samples without allocating once warm).
#[derive(Clone, Debug, Default)]
pub struct Grouper {
    /// Open-addressing table of key → group number + 1 (0: free), a power of two at least twice the groups.
    table: Vec<u32>,
    /// Per group: its key, its table slot (to free it) and where its items end in `order` (one more entry,
    /// used while counting).
    keys: Vec<u32>,
    slots: Vec<u32>,
    starts: Vec<u32>,
    /// Each item's group number.
    item_group: Vec<u32>,
    /// The items' indices, group after group.
    order: Vec<u32>,
}

/// The smallest table (entries).
const MIN_TABLE: usize = 1024;

/// A key's first table slot (Fibonacci hashing; `mask + 1` a power of two).
#[inline(always)]
fn home(key: u32, mask: usize) -> usize {
    (key.wrapping_mul(0x9e37_79b9) as usize ^ (key as usize >> 16)) & mask
}

impl Grouper {
    /// Groups the items `0..keys.len()` by key; [`Grouper::groups`] then lists them.
    pub fn group(&mut self, keys: impl ExactSizeIterator<Item = u32>) {
        if self.table.len() < MIN_TABLE {
            self.table = vec![0; MIN_TABLE];
        }
        // Free the previous call's slots (only they are set).
        for &s in &self.slots {
            self.table[s as usize] = 0;
        }
        self.keys.clear();
        self.slots.clear();
        self.starts.clear();
        self.item_group.clear();
        self.item_group.reserve(keys.len());
        for key in keys {
            let g = self.find_or_insert(key);
            self.item_group.push(g);
        }
        // Counts, then their prefix sums: each group's first position in `order`.
        self.starts.resize(self.keys.len() + 1, 0);
        for &g in &self.item_group {
            self.starts[g as usize + 1] += 1;
        }
        for g in 1..self.starts.len() {
            self.starts[g] += self.starts[g - 1];
        }
        self.order.clear();
        self.order.resize(self.item_group.len(), 0);
        // Items in increasing index order, so each group's list is increasing; each group's start moves to its
        // end, the next group's start.
        for (i, &g) in self.item_group.iter().enumerate() {
            let at = &mut self.starts[g as usize];
            self.order[*at as usize] = i as u32;
            *at += 1;
        }
    }

    /// The groups of the last [`Grouper::group`], in order of their keys' first appearance: each the items'
    /// indices in increasing order.
    pub fn groups(&self) -> impl Iterator<Item = &[u32]> {
        // After the scatter, `starts[g]` is where group `g` ends.
        (0..self.keys.len()).map(|g| {
            let begin = if g == 0 { 0 } else { self.starts[g - 1] };
            &self.order[begin as usize..self.starts[g] as usize]
        })
    }

    /// The group number of `key`, a new one where it is new.
    #[inline]
    fn find_or_insert(&mut self, key: u32) -> u32 {
        let mask = self.table.len() - 1;
        let mut s = home(key, mask);
        loop {
            match self.table[s] {
                0 => break,
                g if self.keys[g as usize - 1] == key => return g - 1,
                _ => s = (s + 1) & mask,
            }
        }
        let g = self.keys.len() as u32;
        self.keys.push(key);
        self.slots.push(s as u32);
        self.table[s] = g + 1;
        if 2 * self.keys.len() > self.table.len() {
            self.grow();
        }
        g
    }

    /// Doubles the table and places every group again.
    fn grow(&mut self) {
        self.table = vec![0; self.table.len() * 2];
        let mask = self.table.len() - 1;
        for (g, &key) in self.keys.iter().enumerate() {
            let mut s = home(key, mask);
            while self.table[s] != 0 {
                s = (s + 1) & mask;
            }
            self.table[s] = g as u32 + 1;
            self.slots[g] = s as u32;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// The groups as a sort of `(key, index)` pairs makes them, by key.
    fn by_sort(keys: &[u32]) -> Vec<(u32, Vec<u32>)> {
        let mut pairs: Vec<(u32, u32)> = keys.iter().enumerate().map(|(i, &k)| (k, i as u32)).collect();
        pairs.sort_unstable();
        pairs
            .chunk_by(|a, b| a.0 == b.0)
            .map(|run| (run[0].0, run.iter().map(|p| p.1).collect()))
            .collect()
    }

    fn check(grouper: &mut Grouper, keys: &[u32]) -> Result<(), TestCaseError> {
        grouper.group(keys.iter().copied());
        let mut got: Vec<(u32, Vec<u32>)> = grouper.groups().map(|g| (keys[g[0] as usize], g.to_vec())).collect();
        // First appearance order: each group's first item comes after the previous group's first item.
        prop_assert!(got.windows(2).all(|w| w[0].1[0] < w[1].1[0]));
        got.sort_unstable();
        prop_assert_eq!(got, by_sort(keys));
        Ok(())
    }

    proptest! {
        #[test]
        fn groups_equal_those_of_a_sort(
            few in proptest::collection::vec(0u32..40, 0..300),
            many in proptest::collection::vec(any::<u32>(), 0..3000),
        ) {
            // One grouper for all calls: slots freed between calls, a table grown past its first size.
            let mut grouper = Grouper::default();
            check(&mut grouper, &few)?;
            check(&mut grouper, &many)?;
            check(&mut grouper, &few)?;
            check(&mut grouper, &[])?;
        }
    }
}
