//! The compiled form of an `expression` model: a straight-line program of column
//! operations. Each instruction applies one operation to whole columns of a block (an
//! input's column, a register's, or a constant), so a block of n rows costs one dispatch
//! per instruction rather than a tree walk or a name look-up per sample, and every loop
//! body is one arithmetic operation the compiler can vectorise. Every row is computed
//! alone with the same operations in the same order, so the values do not depend on how
//! the rows are cut into blocks, chunks, threads or shards.
//!
//! Semantics beyond IEEE arithmetic: a comparison or a logical operation gives 1 or 0,
//! and NaN when an operand is not finite (NaN, or ±inf from a division by zero or an
//! overflow: a failed sample stays failed instead of turning into a plain 1 or 0); `min`
//! and `max` give NaN when an operand is not finite (Rust's `f64::min` would hide a NaN);
//! `c ? a : b` takes `a` where c ≠ 0, `b` where c = 0 and NaN where c is not finite; both
//! branches are computed for every row (they have no side effects).

use std::cell::RefCell;

/// Functions of one argument (and the prefix operators).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Unary {
    /// −x.
    Negate,
    /// 1 where x = 0, else 0.
    Not,
    /// sin x (x in rad).
    Sin,
    /// cos x.
    Cos,
    /// tan x.
    Tan,
    /// asin x (rad).
    Asin,
    /// acos x.
    Acos,
    /// atan x.
    Atan,
    /// √x.
    Sqrt,
    /// eˣ.
    Exp,
    /// ln x.
    Ln,
    /// log₁₀ x.
    Log10,
    /// |x|.
    Abs,
    /// ⌊x⌋.
    Floor,
    /// ⌈x⌉.
    Ceil,
    /// xᵏ for a whole constant k (repeated multiplication, `f64::powi`).
    Powi(i32),
}

/// Functions of two arguments (and the binary operators).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Binary {
    /// a + b.
    Add,
    /// a − b.
    Subtract,
    /// a·b.
    Multiply,
    /// a / b.
    Divide,
    /// aᵇ (`f64::powf`).
    Power,
    /// atan2(a, b): the angle of the point (b, a).
    Atan2,
    /// √(a² + b²) without overflow (`f64::hypot`).
    Hypot,
    /// The smaller, NaN when either is not finite.
    Min,
    /// The larger, NaN when either is not finite.
    Max,
    /// a < b.
    Less,
    /// a ≤ b.
    LessEqual,
    /// a > b.
    Greater,
    /// a ≥ b.
    GreaterEqual,
    /// a = b.
    Equal,
    /// a ≠ b.
    NotEqual,
    /// a ≠ 0 and b ≠ 0.
    And,
    /// a ≠ 0 or b ≠ 0.
    Or,
}

/// Where an instruction reads a value.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Operand {
    /// The same number for every row.
    Constant(f64),
    /// The model's input of this index.
    Input(usize),
    /// A register written by an earlier instruction.
    Register(usize),
}

/// One column operation.
#[derive(Debug, Clone, PartialEq)]
pub enum Instruction {
    /// `to = op(a)`.
    Unary {
        /// Operation.
        op: Unary,
        /// Argument.
        a: Operand,
        /// Register written.
        to: usize,
    },
    /// `to = op(a, b)`.
    Binary {
        /// Operation.
        op: Binary,
        /// First argument.
        a: Operand,
        /// Second argument.
        b: Operand,
        /// Register written.
        to: usize,
    },
    /// `to = condition ? then : otherwise`.
    Select {
        /// Condition.
        condition: Operand,
        /// Value where it is not zero.
        then: Operand,
        /// Value where it is zero.
        otherwise: Operand,
        /// Register written.
        to: usize,
    },
}

/// A compiled expression model: its instructions, how many registers they use and
/// where each output is read.
#[derive(Debug, Clone, PartialEq)]
pub struct Program {
    /// The instructions in order.
    pub instructions: Vec<Instruction>,
    /// Registers used (0 … registers − 1); no instruction writes a register it reads.
    pub registers: usize,
    /// Where output j is read after the last instruction.
    pub outputs: Vec<Operand>,
}

/// 1 or 0 for a truth value, NaN when an operand was not finite.
#[inline(always)]
fn truth(nan: bool, value: bool) -> f64 {
    if nan {
        f64::NAN
    } else if value {
        1.0
    } else {
        0.0
    }
}

impl Unary {
    /// The operation on one number.
    #[inline(always)]
    pub fn apply(self, x: f64) -> f64 {
        match self {
            Unary::Negate => -x,
            Unary::Not => truth(!x.is_finite(), x == 0.0),
            Unary::Sin => x.sin(),
            Unary::Cos => x.cos(),
            Unary::Tan => x.tan(),
            Unary::Asin => x.asin(),
            Unary::Acos => x.acos(),
            Unary::Atan => x.atan(),
            Unary::Sqrt => x.sqrt(),
            Unary::Exp => x.exp(),
            Unary::Ln => x.ln(),
            Unary::Log10 => x.log10(),
            Unary::Abs => x.abs(),
            Unary::Floor => x.floor(),
            Unary::Ceil => x.ceil(),
            Unary::Powi(k) => x.powi(k),
        }
    }
}

impl Binary {
    /// The operation on two numbers.
    #[inline(always)]
    pub fn apply(self, a: f64, b: f64) -> f64 {
        let nan = !(a.is_finite() && b.is_finite());
        match self {
            Binary::Add => a + b,
            Binary::Subtract => a - b,
            Binary::Multiply => a * b,
            Binary::Divide => a / b,
            Binary::Power => a.powf(b),
            Binary::Atan2 => a.atan2(b),
            Binary::Hypot => a.hypot(b),
            Binary::Min => {
                if nan {
                    f64::NAN
                } else {
                    a.min(b)
                }
            }
            Binary::Max => {
                if nan {
                    f64::NAN
                } else {
                    a.max(b)
                }
            }
            Binary::Less => truth(nan, a < b),
            Binary::LessEqual => truth(nan, a <= b),
            Binary::Greater => truth(nan, a > b),
            Binary::GreaterEqual => truth(nan, a >= b),
            Binary::Equal => truth(nan, a == b),
            Binary::NotEqual => truth(nan, a != b),
            Binary::And => truth(nan, a != 0.0 && b != 0.0),
            Binary::Or => truth(nan, a != 0.0 || b != 0.0),
        }
    }
}

/// `condition ? then : otherwise` on one row.
#[inline(always)]
pub fn select(condition: f64, then: f64, otherwise: f64) -> f64 {
    if !condition.is_finite() {
        f64::NAN
    } else if condition != 0.0 {
        then
    } else {
        otherwise
    }
}

/// The inputs of a run: a block's columns, or one row.
#[derive(Clone, Copy)]
pub enum Inputs<'a> {
    /// `columns[i]` holds input i of every row of the block.
    Columns(&'a [&'a [f64]]),
    /// Input i of the one row.
    Row(&'a [f64]),
}

/// An operand as the loops read it: a column of the block, or one number for every row.
#[derive(Clone, Copy)]
enum Source<'a> {
    Column(&'a [f64]),
    Scalar(f64),
}

impl Source<'_> {
    #[inline(always)]
    fn at(&self, r: usize) -> f64 {
        match self {
            Source::Column(column) => column[r],
            Source::Scalar(x) => *x,
        }
    }
}

thread_local! {
    /// The registers of the runs on this thread, kept between blocks.
    static REGISTERS: RefCell<Vec<Vec<f64>>> = const { RefCell::new(Vec::new()) };
}

impl Program {
    /// Runs the program on `n` rows of `inputs` and writes output j of row r to
    /// `outputs[j·n + r]`.
    pub fn run(&self, n: usize, inputs: Inputs, outputs: &mut [f64]) {
        REGISTERS.with(|registers| {
            let mut registers = registers.borrow_mut();
            if registers.len() < self.registers {
                registers.resize_with(self.registers, Vec::new);
            }
            for register in registers.iter_mut().take(self.registers) {
                register.resize(n, 0.0);
            }
            for instruction in &self.instructions {
                execute(instruction, n, inputs, &mut registers);
            }
            for (j, &operand) in self.outputs.iter().enumerate() {
                let to = &mut outputs[j * n..(j + 1) * n];
                match source(operand, inputs, &registers) {
                    Source::Column(column) => to.copy_from_slice(&column[..n]),
                    Source::Scalar(x) => to.fill(x),
                }
            }
        });
    }
}

fn source<'a>(operand: Operand, inputs: Inputs<'a>, registers: &'a [Vec<f64>]) -> Source<'a> {
    match (operand, inputs) {
        (Operand::Constant(x), _) => Source::Scalar(x),
        (Operand::Input(i), Inputs::Columns(columns)) => Source::Column(columns[i]),
        (Operand::Input(i), Inputs::Row(row)) => Source::Scalar(row[i]),
        (Operand::Register(k), _) => Source::Column(&registers[k]),
    }
}

/// Runs one instruction. The register written is taken out of the file while the loop
/// runs (the program never reads a register it writes in the same instruction).
fn execute(instruction: &Instruction, n: usize, inputs: Inputs, registers: &mut [Vec<f64>]) {
    let to = match instruction {
        Instruction::Unary { to, .. }
        | Instruction::Binary { to, .. }
        | Instruction::Select { to, .. } => *to,
    };
    let mut out = std::mem::take(&mut registers[to]);
    let out_slice = &mut out[..n];
    match *instruction {
        Instruction::Unary { op, a, .. } => unary(op, source(a, inputs, registers), out_slice),
        Instruction::Binary { op, a, b, .. } => binary(
            op,
            source(a, inputs, registers),
            source(b, inputs, registers),
            out_slice,
        ),
        Instruction::Select {
            condition,
            then,
            otherwise,
            ..
        } => {
            let (c, a, b) = (
                source(condition, inputs, registers),
                source(then, inputs, registers),
                source(otherwise, inputs, registers),
            );
            for (r, y) in out_slice.iter_mut().enumerate() {
                *y = select(c.at(r), a.at(r), b.at(r));
            }
        }
    }
    registers[to] = out;
}

/// `out[r] = f(a[r])`, one loop per shape of the operand.
#[inline(always)]
fn map1(a: Source, out: &mut [f64], f: impl Fn(f64) -> f64) {
    match a {
        Source::Column(a) => {
            for (y, &x) in out.iter_mut().zip(a) {
                *y = f(x);
            }
        }
        Source::Scalar(x) => out.fill(f(x)),
    }
}

/// `out[r] = f(a[r], b[r])`, one loop per shape of the operands.
#[inline(always)]
fn map2(a: Source, b: Source, out: &mut [f64], f: impl Fn(f64, f64) -> f64) {
    match (a, b) {
        (Source::Column(a), Source::Column(b)) => {
            for ((y, &x), &z) in out.iter_mut().zip(a).zip(b) {
                *y = f(x, z);
            }
        }
        (Source::Column(a), Source::Scalar(z)) => {
            for (y, &x) in out.iter_mut().zip(a) {
                *y = f(x, z);
            }
        }
        (Source::Scalar(x), Source::Column(b)) => {
            for (y, &z) in out.iter_mut().zip(b) {
                *y = f(x, z);
            }
        }
        (Source::Scalar(x), Source::Scalar(z)) => out.fill(f(x, z)),
    }
}

/// One unary instruction: the match on the operation is outside the loop, so each loop
/// is monomorphic.
fn unary(op: Unary, a: Source, out: &mut [f64]) {
    macro_rules! each {
        ($($variant:ident),*) => {
            match op {
                $(Unary::$variant => map1(a, out, |x| Unary::$variant.apply(x)),)*
                Unary::Powi(k) => map1(a, out, |x| x.powi(k)),
            }
        };
    }
    each!(Negate, Not, Sin, Cos, Tan, Asin, Acos, Atan, Sqrt, Exp, Ln, Log10, Abs, Floor, Ceil)
}

/// One binary instruction (see [`unary`]).
fn binary(op: Binary, a: Source, b: Source, out: &mut [f64]) {
    macro_rules! each {
        ($($variant:ident),*) => {
            match op {
                $(Binary::$variant => map2(a, b, out, |x, z| Binary::$variant.apply(x, z)),)*
            }
        };
    }
    each!(
        Add,
        Subtract,
        Multiply,
        Divide,
        Power,
        Atan2,
        Hypot,
        Min,
        Max,
        Less,
        LessEqual,
        Greater,
        GreaterEqual,
        Equal,
        NotEqual,
        And,
        Or
    )
}
