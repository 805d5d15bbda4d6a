//! The one counter type every traversal of every structure fills, named as
//! in the reports (docs/design.md, "Metrics").

/// Work done by one trace call (one ray or an array of rays), for any
/// structure. Fields a structure has no use for stay 0.
///
/// `traversal_steps` is the TSPR numerator: nodes visited, interior and
/// leaf. The thesis' cost units (Bezerianos 2001, 4.1: add, multiply,
/// compare 1, divide 5, square root 15) are counted by the hierarchies.
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
    /// Hierarchies: hierarchy objects (3D boxes and 2D rectangles) tested.
    pub box_tests: u64,
    /// Hierarchies: their cost in the thesis' units.
    pub box_cost: u64,
    /// Hierarchies: cost of the primitives tested, in the thesis' units.
    pub prim_cost: u64,
    /// Projection hierarchies: point-in-rectangle tests among `box_tests`.
    pub rect_tests: u64,
    /// Rays whose traversal stopped at a broken invariant of the structure
    /// (an index out of range, a cycle, a stack too short for the tree).
    /// Always 0 on a structure that `validate` accepted; the C ABI turns
    /// any other count into `CORAY_STATUS_CORRUPT_ARENA`.
    pub faults: u64,
}

impl TraceStats {
    /// Adds another call's counts to these, modulo 2^64: the sums may
    /// start from any bits (a C tracer keeps them in caller memory), and no
    /// build's overflow checks may panic on them.
    pub fn add(&mut self, o: &TraceStats) {
        self.rays = self.rays.wrapping_add(o.rays);
        self.traversal_steps = self.traversal_steps.wrapping_add(o.traversal_steps);
        self.interior_steps = self.interior_steps.wrapping_add(o.interior_steps);
        self.leaf_steps = self.leaf_steps.wrapping_add(o.leaf_steps);
        self.empty_leaf_steps = self.empty_leaf_steps.wrapping_add(o.empty_leaf_steps);
        self.prim_tests = self.prim_tests.wrapping_add(o.prim_tests);
        self.box_tests = self.box_tests.wrapping_add(o.box_tests);
        self.box_cost = self.box_cost.wrapping_add(o.box_cost);
        self.prim_cost = self.prim_cost.wrapping_add(o.prim_cost);
        self.rect_tests = self.rect_tests.wrapping_add(o.rect_tests);
        self.faults = self.faults.wrapping_add(o.faults);
    }

    /// Traversal steps per ray (TSPR).
    pub fn tspr(&self) -> f64 {
        self.traversal_steps as f64 / self.rays.max(1) as f64
    }

    /// Primitive tests per ray.
    pub fn tests_per_ray(&self) -> f64 {
        self.prim_tests as f64 / self.rays.max(1) as f64
    }

    /// The thesis' average cost per hierarchy object.
    pub fn cost_per_box(&self) -> f64 {
        self.box_cost as f64 / self.box_tests.max(1) as f64
    }

    /// The thesis' average cost per actual object (primitive).
    pub fn cost_per_prim(&self) -> f64 {
        self.prim_cost as f64 / self.prim_tests.max(1) as f64
    }
}
