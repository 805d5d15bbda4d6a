//! Counters that every traversal fills, named as in the reports (DESIGN.md).

/// Work done by one trace call (one ray or an array of rays).
///
/// `traversal_steps` is the TSPR numerator: nodes visited, interior and leaf.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[repr(C)]
pub struct TraceStats {
    /// Rays traced.
    pub rays: u64,
    /// Nodes visited, interior plus leaf.
    pub traversal_steps: u64,
    /// Interior nodes visited.
    pub interior_steps: u64,
    /// Leaves visited (empty or not).
    pub leaf_steps: u64,
    /// Leaves visited that hold no primitive.
    pub empty_leaf_steps: u64,
    /// Ray-primitive intersection tests.
    pub prim_tests: u64,
}

impl TraceStats {
    /// Adds another call's counts to these.
    pub fn add(&mut self, other: &TraceStats) {
        self.rays += other.rays;
        self.traversal_steps += other.traversal_steps;
        self.interior_steps += other.interior_steps;
        self.leaf_steps += other.leaf_steps;
        self.empty_leaf_steps += other.empty_leaf_steps;
        self.prim_tests += other.prim_tests;
    }
}
