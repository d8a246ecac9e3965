//! When more parts stop helping: with the optional MOV tolerance, once only MOV is out of
//! tolerance, refinement stops when MOV has not improved for [`MOV_PATIENCE`] steps. With the
//! whole surface enclosed, a part at a pointed tip keeps a large relative outside volume
//! whatever k; more parts would only add cost.

/// Refinement steps without a better MOV (while only MOV is out of tolerance) after which
/// refinement stops.
pub const MOV_PATIENCE: usize = 6;

/// The best MOV seen while only MOV was out of tolerance, and the steps since it improved.
#[derive(Debug, Clone)]
pub struct MovPatience {
    best: f64,
    stale: usize,
}

impl Default for MovPatience {
    fn default() -> Self {
        Self {
            best: f64::INFINITY,
            stale: 0,
        }
    }
}

impl MovPatience {
    /// Record a step's MOV; `true` when patience has run out and refinement should stop.
    pub fn run_out(&mut self, mov: f64) -> bool {
        if mov < self.best {
            self.best = mov;
            self.stale = 0;
            false
        } else {
            self.stale += 1;
            self.stale > MOV_PATIENCE
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stops_after_patience_steps_without_gain_and_resets_on_gain() {
        let mut p = MovPatience::default();
        assert!(!p.run_out(1.0));
        for _ in 0..MOV_PATIENCE {
            assert!(!p.run_out(1.0));
        }
        // A better MOV resets the count.
        assert!(!p.run_out(0.9));
        for _ in 0..MOV_PATIENCE {
            assert!(!p.run_out(0.95));
        }
        assert!(p.run_out(0.9), "an equal MOV is no gain");
    }
}
