//! The result table of the benchmarks, with budgets. `#[inline]` for the reason the meter's
//! functions are (see [`crate::meter`]): compiled with each benchmark.

pub struct Row {
    pub what: &'static str,
    pub value: f32,
    pub unit: &'static str,
    pub budget: Option<f32>,
}

pub struct Table {
    rows: heapless::Vec<Row, 32>,
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
