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

use naga::{
    BinaryOperator, Expression, MathFunction, Scalar, ScalarKind, TypeInner, UnaryOperator,
};

use super::{source, Arithmetic, Entry};

/// The kinds of f64 operation counted, in the table's column order.
#[derive(Clone, Copy, Debug)]
enum F64Op {
    ToF64,
    FromF64,
    /// Additions, subtractions and negations.
    AddSub,
    Mul,
    Div,
    Sqrt,
}

/// f64 operations, counted per [`F64Op`] (indexed by it).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
struct F64Work([u32; 6]);

impl F64Work {
    const NONE: F64Work = F64Work([0; 6]);

    /// `lanes` operations of kind `op`.
    fn of(op: F64Op, lanes: u32) -> F64Work {
        let mut counts = [0; 6];
        counts[op as usize] = lanes;
        F64Work(counts)
    }

    fn total(self) -> u32 {
        self.0.iter().sum()
    }
}

impl Add for F64Work {
    type Output = F64Work;
    fn add(self, other: F64Work) -> F64Work {
        F64Work(std::array::from_fn(|op| self.0[op] + other.0[op]))
    }
}

impl std::iter::Sum for F64Work {
    fn sum<I: Iterator<Item = F64Work>>(iter: I) -> F64Work {
        iter.fold(F64Work::NONE, Add::add)
    }
}

impl fmt::Display for F64Work {
    fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
        for count in self.0 {
            write!(f, "{count} | ")?;
        }
        write!(f, "**{}**", self.total())
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
            .filter_map(|(handle, expression)| {
                let op = match *expression {
                    Expression::As {
                        expr,
                        kind: ScalarKind::Float,
                        convert: Some(8),
                    } if lanes(expr) == 0 => F64Op::ToF64,
                    Expression::As {
                        expr,
                        convert: Some(width),
                        ..
                    } if width != 8 => return Some(F64Work::of(F64Op::FromF64, lanes(expr))),
                    Expression::Binary { op, .. } => match op {
                        BinaryOperator::Add | BinaryOperator::Subtract => F64Op::AddSub,
                        BinaryOperator::Multiply => F64Op::Mul,
                        BinaryOperator::Divide => F64Op::Div,
                        _ => {
                            assert_eq!(lanes(handle), 0, "an f64 {op:?} left uncounted");
                            return None;
                        }
                    },
                    Expression::Unary {
                        op: UnaryOperator::Negate,
                        ..
                    } => F64Op::AddSub,
                    Expression::Math {
                        fun: MathFunction::Sqrt,
                        ..
                    } => F64Op::Sqrt,
                    Expression::Math { fun, .. } => {
                        assert_eq!(lanes(handle), 0, "an f64 {fun:?} left uncounted");
                        return None;
                    }
                    _ => return None,
                };
                Some(F64Work::of(op, lanes(handle)))
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
    // To f64, from f64, add/sub, mul, div, sqrt.
    assert_eq!(analysed.work_of("mul"), F64Work([2, 1, 0, 1, 0, 0]));
    assert_eq!(analysed.work_of("div"), F64Work([2, 1, 0, 0, 1, 0]));
    assert_eq!(analysed.work_of("root"), F64Work([1, 1, 0, 0, 0, 1]));
    assert_eq!(
        analysed.work_of("difference_of_products"),
        F64Work([4, 1, 1, 2, 0, 0])
    );
    assert_eq!(
        analysed.work_of("triangle_normal"),
        F64Work([12, 3, 11, 12, 1, 1])
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
