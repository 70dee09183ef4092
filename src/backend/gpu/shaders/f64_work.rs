//! How much f64 work the tracing passes do per traversal step, per
//! triangle test and per ray: conversions to and from f64 and f64
//! arithmetic, counted in naga's IR of the modules [`super::source`]
//! assembles, for each [`Arithmetic`]. On consumer GPUs f64 runs at 1/32
//! to 1/64 of f32's rate (Metal has none), so these figures are what the
//! CPU's rounding costs there; the tests pin them, so a change that adds
//! f64 work to a hot path fails here, and `cargo test --lib f64_work --
//! --nocapture` prints the tables BENCHMARKS.md quotes (with each pass's
//! total over all its code).
//!
//! The count is static: each operation in a function's code counts once,
//! and each call counts its callee's work once, whether it stands in a
//! branch taken rarely or a loop body run three times. Vector operations
//! count once per component.

use std::fmt;
use std::ops::Add;

use naga::{BinaryOperator, Expression, MathFunction, Scalar, ScalarKind, TypeInner};

use super::{source, Arithmetic, Entry};

/// f64 operations, by kind; vector operations count per component.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
struct F64Work {
    to_f64: u32,
    from_f64: u32,
    /// Additions, subtractions and negations.
    add_sub: u32,
    mul: u32,
    div: u32,
    sqrt: u32,
}

impl F64Work {
    const NONE: F64Work = F64Work {
        to_f64: 0,
        from_f64: 0,
        add_sub: 0,
        mul: 0,
        div: 0,
        sqrt: 0,
    };

    fn total(self) -> u32 {
        self.to_f64 + self.from_f64 + self.add_sub + self.mul + self.div + self.sqrt
    }
}

impl Add for F64Work {
    type Output = F64Work;
    fn add(self, other: F64Work) -> F64Work {
        F64Work {
            to_f64: self.to_f64 + other.to_f64,
            from_f64: self.from_f64 + other.from_f64,
            add_sub: self.add_sub + other.add_sub,
            mul: self.mul + other.mul,
            div: self.div + other.div,
            sqrt: self.sqrt + other.sqrt,
        }
    }
}

impl std::iter::Sum for F64Work {
    fn sum<I: Iterator<Item = F64Work>>(iter: I) -> F64Work {
        iter.fold(F64Work::NONE, Add::add)
    }
}

impl fmt::Display for F64Work {
    fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
        write!(
            f,
            "{} | {} | {} | {} | {} | {} | **{}**",
            self.to_f64,
            self.from_f64,
            self.add_sub,
            self.mul,
            self.div,
            self.sqrt,
            self.total()
        )
    }
}

/// The f64 lanes of a value of type `inner`: 1 for an f64, n for an
/// n-vector of them, else 0.
fn f64_lanes(inner: &TypeInner) -> u32 {
    match *inner {
        TypeInner::Scalar(Scalar::F64) => 1,
        TypeInner::Vector {
            size,
            scalar: Scalar::F64,
        } => size as u32,
        _ => 0,
    }
}

/// A module validated, with the types of its expressions.
struct Analysed {
    module: naga::Module,
    info: naga::valid::ModuleInfo,
}

impl Analysed {
    /// The tracing passes' module (closest hit: the world, the triangle
    /// test and the traversal) as `arithmetic` assembles it.
    fn tracing(arithmetic: Arithmetic) -> Analysed {
        Analysed::pass(Entry::ClosestHit, arithmetic)
    }

    /// `entry`'s module as `arithmetic` assembles it.
    fn pass(entry: Entry, arithmetic: Arithmetic) -> Analysed {
        let module = naga::front::wgsl::parse_str(&source(entry, arithmetic))
            .unwrap_or_else(|e| panic!("{arithmetic:?}: {e}"));
        let info = naga::valid::Validator::new(
            naga::valid::ValidationFlags::all(),
            arithmetic.capabilities(),
        )
        .validate(&module)
        .unwrap_or_else(|e| panic!("{arithmetic:?}: {e:?}"));
        Analysed { module, info }
    }

    /// The function or entry point named `name`, with its types.
    fn function(&self, name: &str) -> (&naga::Function, &naga::valid::FunctionInfo) {
        let function = (self.module.functions.iter())
            .find(|(_, function)| function.name.as_deref() == Some(name))
            .map(|(handle, function)| (function, &self.info[handle]));
        let entry_point = || {
            (self.module.entry_points.iter().enumerate())
                .find(|(_, entry)| entry.name == name)
                .map(|(at, entry)| (&entry.function, self.info.get_entry_point(at)))
        };
        function
            .or_else(entry_point)
            .unwrap_or_else(|| panic!("no function {name}"))
    }

    /// The f64 work of one call of `body`, its callees' included.
    fn work(&self, body: &naga::Function, info: &naga::valid::FunctionInfo) -> F64Work {
        let lanes = |expression: naga::Handle<Expression>| {
            f64_lanes(info[expression].ty.inner_with(&self.module.types))
        };
        let own: F64Work = (body.expressions.iter())
            .map(|(handle, expression)| match *expression {
                Expression::As {
                    expr,
                    kind: ScalarKind::Float,
                    convert: Some(8),
                } if lanes(expr) == 0 => F64Work {
                    to_f64: lanes(handle),
                    ..F64Work::NONE
                },
                Expression::As {
                    expr,
                    convert: Some(width),
                    ..
                } if width != 8 => F64Work {
                    from_f64: lanes(expr),
                    ..F64Work::NONE
                },
                Expression::Binary { op, .. } => {
                    let n = lanes(handle);
                    match op {
                        BinaryOperator::Add | BinaryOperator::Subtract => F64Work {
                            add_sub: n,
                            ..F64Work::NONE
                        },
                        BinaryOperator::Multiply => F64Work {
                            mul: n,
                            ..F64Work::NONE
                        },
                        BinaryOperator::Divide => F64Work {
                            div: n,
                            ..F64Work::NONE
                        },
                        _ => {
                            assert_eq!(n, 0, "an f64 {op:?} this count does not classify");
                            F64Work::NONE
                        }
                    }
                }
                Expression::Unary { .. } => F64Work {
                    add_sub: lanes(handle),
                    ..F64Work::NONE
                },
                Expression::Math { fun, .. } => {
                    let n = lanes(handle);
                    match fun {
                        MathFunction::Sqrt => F64Work {
                            sqrt: n,
                            ..F64Work::NONE
                        },
                        _ => {
                            assert_eq!(n, 0, "an f64 {fun:?} this count does not classify");
                            F64Work::NONE
                        }
                    }
                }
                _ => F64Work::NONE,
            })
            .sum();
        let mut callees = Vec::new();
        calls(&body.body, &mut callees);
        let callees = callees
            .into_iter()
            .map(|callee| self.work(&self.module.functions[callee], &self.info[callee]));
        own + callees.sum()
    }

    fn work_of(&self, name: &str) -> F64Work {
        let (body, info) = self.function(name);
        self.work(body, info)
    }
}

/// Every function `block` calls, once per call statement.
fn calls(block: &naga::Block, out: &mut Vec<naga::Handle<naga::Function>>) {
    for statement in block.iter() {
        match statement {
            naga::Statement::Call { function, .. } => out.push(*function),
            naga::Statement::Block(inner) => calls(inner, out),
            naga::Statement::If { accept, reject, .. } => {
                calls(accept, out);
                calls(reject, out);
            }
            naga::Statement::Loop {
                body, continuing, ..
            } => {
                calls(body, out);
                calls(continuing, out);
            }
            naga::Statement::Switch { cases, .. } => {
                cases.iter().for_each(|case| calls(&case.body, out));
            }
            _ => {}
        }
    }
}

/// The functions the table reports, with what one call of each is.
const REPORTED: [(&str, &str); 7] = [
    ("enter_child", "traversal step (wide node): one child's box"),
    ("enter_box", "traversal step (binary node): one box"),
    ("intersect_triangle", "triangle test, every path"),
    (
        "difference_of_products",
        "its tie-breaker, 3 calls where an edge function rounds to 0",
    ),
    ("watertight_ray", "ray setup: the triangle test's shear"),
    (
        "traversal_ray",
        "ray setup: the box tests' inverse direction",
    ),
    (
        "to_object_vector",
        "instance setup: a map's loop body (3 runs a map, 2 maps)",
    ),
];

/// The f64 work of each reported function under `arithmetic`.
fn reported(arithmetic: Arithmetic) -> Vec<F64Work> {
    let analysed = Analysed::tracing(arithmetic);
    REPORTED
        .iter()
        .map(|(name, _)| analysed.work_of(name))
        .collect()
}

/// Prints the tables BENCHMARKS.md quotes: one row per function and
/// arithmetic, then each pass's total over all its code.
#[test]
fn print_f64_work_per_traversal_step_and_triangle_test() {
    println!("| function | one call is | arithmetic | to f64 | from f64 | add/sub | mul | div | sqrt | total |");
    println!("|---|---|---|---|---|---|---|---|---|---|");
    for arithmetic in Arithmetic::ALL {
        for ((name, what), work) in REPORTED.iter().zip(reported(arithmetic)) {
            println!("| `{name}` | {what} | {arithmetic:?} | {work} |");
        }
    }
    println!();
    println!("| pass: every code path, each call once | ExactF64 | ExactUncontracted |");
    println!("|---|---|---|");
    for entry in Entry::ALL {
        let total = |arithmetic| {
            let analysed = Analysed::pass(entry, arithmetic);
            analysed.work_of(entry.name()).total()
        };
        let (before, after) = (
            total(Arithmetic::ExactF64),
            total(Arithmetic::ExactUncontracted),
        );
        println!("| `{}` | {before} | {after} |", entry.pipeline_name());
    }
}

/// The helpers' own cost, by hand from `product_f64.wgsl` and
/// `exact_f64.wgsl`: what the pinned figures below are made of.
#[test]
fn each_f64_helper_costs_what_its_wgsl_says() {
    let analysed = Analysed::tracing(Arithmetic::ExactF64);
    let work = |to_f64, from_f64, add_sub, mul, div, sqrt| F64Work {
        to_f64,
        from_f64,
        add_sub,
        mul,
        div,
        sqrt,
    };
    assert_eq!(analysed.work_of("mul"), work(2, 1, 0, 1, 0, 0));
    assert_eq!(analysed.work_of("div"), work(2, 1, 0, 0, 1, 0));
    assert_eq!(analysed.work_of("root"), work(1, 1, 0, 0, 0, 1));
    assert_eq!(
        analysed.work_of("difference_of_products"),
        work(4, 1, 1, 2, 0, 0)
    );
    let uncontracted = Analysed::tracing(Arithmetic::ExactUncontracted);
    assert_eq!(uncontracted.work_of("mul"), F64Work::NONE);
    assert_eq!(uncontracted.work_of("div"), analysed.work_of("div"));
}

/// The totals per function, pinned: more f64 work on a traced path
/// fails here (and BENCHMARKS.md's table wants updating).
#[test]
fn f64_work_per_traversal_step_and_triangle_test_is_pinned() {
    let totals = |arithmetic| -> Vec<u32> {
        reported(arithmetic)
            .into_iter()
            .map(F64Work::total)
            .collect()
    };
    // enter_child, enter_box, intersect_triangle, difference_of_products,
    // watertight_ray, traversal_ray, to_object_vector.
    assert_eq!(totals(Arithmetic::ExactF64), [0, 0, 112, 8, 12, 12, 12]);
    assert_eq!(
        totals(Arithmetic::ExactUncontracted),
        [0, 0, 28, 8, 12, 12, 0]
    );
    assert_eq!(totals(Arithmetic::PlainF32), [0; 7]);
}
