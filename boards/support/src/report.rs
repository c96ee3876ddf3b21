//! The result table of the benchmarks, with budgets. `#[inline]` for the reason the meter's
//! functions are (see [`crate::meter`]): compiled with each benchmark.

pub struct Row {
    pub what: &'static str,
    pub value: f32,
    pub unit: &'static str,
    pub budget: Option<f32>,
}

pub struct Table {
    rows: heapless::Vec<Row, 40>,
}

impl Default for Table {
    fn default() -> Self {
        Self::new()
    }
}

impl Table {
    pub const fn new() -> Self {
        Table {
            rows: heapless::Vec::new(),
        }
    }

    #[inline]
    pub fn add(&mut self, what: &'static str, value: f32, unit: &'static str) {
        self.push(what, value, unit, None);
    }

    #[inline]
    pub fn budget(&mut self, what: &'static str, value: f32, unit: &'static str, max: f32) {
        self.push(what, value, unit, Some(max));
    }

    fn push(&mut self, what: &'static str, value: f32, unit: &'static str, budget: Option<f32>) {
        let row = Row {
            what,
            value,
            unit,
            budget,
        };
        if self.rows.push(row).is_err() {
            println!("result table full");
            crate::qemu::exit(false);
        }
    }

    /// Prints the table (Markdown) and returns whether every budget was met.
    #[inline]
    pub fn print(&self) -> bool {
        println!("| measurement | guest instructions | budget | verdict |");
        println!("|---|---:|---:|---|");
        let mut ok = true;
        for r in &self.rows {
            match r.budget {
                Some(max) => {
                    let pass = r.value <= max;
                    ok &= pass;
                    println!(
                        "| {} | {:.1} {} | <= {:.0} | {} |",
                        r.what,
                        r.value,
                        r.unit,
                        max,
                        if pass { "ok" } else { "OVER BUDGET" }
                    );
                }
                None => println!("| {} | {:.1} {} | | |", r.what, r.value, r.unit),
            }
        }
        ok
    }
}

/// A comparison row: the same work done by a baseline and by the crate, and the most the
/// crate may take, as a fraction of the baseline's.
pub struct Versus {
    pub what: &'static str,
    pub baseline: f32,
    pub ours: f32,
    /// The crate's budget is `baseline * ratio`; `None`: shown, not budgeted.
    pub ratio: Option<f32>,
}

/// A table of baseline and crate side by side, with budgets relative to the baseline.
pub struct Comparison {
    baseline: &'static str,
    ours: &'static str,
    rows: heapless::Vec<Versus, 16>,
}

impl Comparison {
    pub const fn new(baseline: &'static str, ours: &'static str) -> Self {
        Comparison {
            baseline,
            ours,
            rows: heapless::Vec::new(),
        }
    }

    /// A row whose crate figure must be at most `ratio` times the baseline's.
    #[inline]
    pub fn row(&mut self, what: &'static str, baseline: f32, ours: f32, ratio: f32) {
        self.push(what, baseline, ours, Some(ratio));
    }

    /// A row shown without a budget.
    #[inline]
    pub fn info(&mut self, what: &'static str, baseline: f32, ours: f32) {
        self.push(what, baseline, ours, None);
    }

    fn push(&mut self, what: &'static str, baseline: f32, ours: f32, ratio: Option<f32>) {
        let row = Versus {
            what,
            baseline,
            ours,
            ratio,
        };
        if self.rows.push(row).is_err() {
            println!("comparison table full");
            crate::qemu::exit(false);
        }
    }

    /// Prints the table (Markdown) and returns whether every budget was met.
    #[inline]
    pub fn print(&self) -> bool {
        println!(
            "| measurement (guest instructions) | {} | {} | budget | verdict |",
            self.baseline, self.ours
        );
        println!("|---|---:|---:|---:|---|");
        let mut ok = true;
        for r in &self.rows {
            let Some(ratio) = r.ratio else {
                println!(
                    "| {} | {:.1} | {:.1} ({:.2} x) | | |",
                    r.what,
                    r.baseline,
                    r.ours,
                    r.ours / r.baseline
                );
                continue;
            };
            let max = r.baseline * ratio;
            let pass = r.ours <= max;
            ok &= pass;
            println!(
                "| {} | {:.1} | {:.1} ({:.2} x) | <= {:.1} ({:.2} x) | {} |",
                r.what,
                r.baseline,
                r.ours,
                r.ours / r.baseline,
                max,
                ratio,
                if pass { "ok" } else { "OVER BUDGET" }
            );
        }
        ok
    }
}
