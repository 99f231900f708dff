//! From the formulas' trees to the [`Program`]: every name resolved (an input, a
//! parameter, `pi`, or a `let` or output defined above), every function's arity checked,
//! operations on constants folded (with the same arithmetic the program runs, so folding
//! changes no bit), `x^k` for a whole constant k turned into `powi`, and registers reused
//! as soon as the value they hold has been read.

use std::collections::{HashMap, HashSet};

use super::parse::{BinaryOp, Node, NodeKind, UnaryOp};
use super::program::{select, Binary, Instruction, Operand, Program, Unary};

/// The functions a formula may call: name, number of arguments (`None`: two or more).
pub const FUNCTIONS: &[(&str, Option<usize>)] = &[
    ("sin", Some(1)),
    ("cos", Some(1)),
    ("tan", Some(1)),
    ("asin", Some(1)),
    ("acos", Some(1)),
    ("atan", Some(1)),
    ("atan2", Some(2)),
    ("sqrt", Some(1)),
    ("hypot", Some(2)),
    ("exp", Some(1)),
    ("ln", Some(1)),
    ("log10", Some(1)),
    ("abs", Some(1)),
    ("min", None),
    ("max", None),
    ("floor", Some(1)),
    ("ceil", Some(1)),
    ("if", Some(3)),
];

/// Names of constants a formula may use.
pub const CONSTANTS: &[(&str, f64)] = &[("pi", std::f64::consts::PI)];

/// Largest |k| for which `x^k` with a whole constant k is computed by multiplication.
const MOST_POWI: f64 = 64.0;

/// A mistake found while compiling a formula: where in it, and what.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct CompileError {
    /// Character position in the formula, from 1.
    pub at: usize,
    /// What is wrong.
    pub message: String,
}

fn error(at: usize, message: impl Into<String>) -> CompileError {
    CompileError {
        at,
        message: message.into(),
    }
}

/// What a name stands for while compiling.
#[derive(Debug, Clone, Copy)]
enum Symbol {
    /// An input of the model.
    Input(usize),
    /// A parameter's value.
    Parameter(f64),
    /// A `let` or an output defined above: where its value is.
    Defined(Operand),
}

/// Compiles formulas one after the other into one program.
pub struct Compiler {
    instructions: Vec<Instruction>,
    registers: usize,
    free: Vec<usize>,
    pinned: HashSet<usize>,
    symbols: HashMap<String, Symbol>,
    /// Names defined by a formula further down (a formula reads only names above it).
    below: HashMap<String, String>,
    /// Names read by some formula.
    read: HashSet<String>,
    outputs: Vec<Operand>,
}

impl Compiler {
    /// A compiler for a model with these inputs and parameters; `below` maps the name of
    /// every `let` and output to the JSON path of its definition.
    pub fn new(
        inputs: &[String],
        parameters: &[(String, f64)],
        below: HashMap<String, String>,
    ) -> Self {
        let mut symbols = HashMap::new();
        for (i, name) in inputs.iter().enumerate() {
            symbols.insert(name.clone(), Symbol::Input(i));
        }
        for (name, value) in parameters {
            symbols.insert(name.clone(), Symbol::Parameter(*value));
        }
        Compiler {
            instructions: Vec::new(),
            registers: 0,
            free: Vec::new(),
            pinned: HashSet::new(),
            symbols,
            below,
            read: HashSet::new(),
            outputs: Vec::new(),
        }
    }

    /// Compiles the formula of `name` (a `let` when `output` is false): from here on
    /// later formulas may read it.
    pub fn define(&mut self, name: &str, node: &Node, output: bool) -> Result<(), CompileError> {
        let operand = self.emit(node)?;
        if let Operand::Register(k) = operand {
            self.pinned.insert(k);
        }
        self.below.remove(name);
        self.symbols
            .insert(name.to_string(), Symbol::Defined(operand));
        if output {
            self.outputs.push(operand);
        }
        Ok(())
    }

    /// Whether some formula read `name`.
    pub fn was_read(&self, name: &str) -> bool {
        self.read.contains(name)
    }

    /// The program.
    pub fn finish(self) -> Program {
        Program {
            instructions: self.instructions,
            registers: self.registers,
            outputs: self.outputs,
        }
    }

    fn allocate(&mut self) -> usize {
        self.free.pop().unwrap_or_else(|| {
            self.registers += 1;
            self.registers - 1
        })
    }

    /// Frees the operands' registers that hold a value nothing reads again.
    fn release(&mut self, operands: &[Operand]) {
        for operand in operands {
            if let Operand::Register(k) = operand {
                if !self.pinned.contains(k) && !self.free.contains(k) {
                    self.free.push(*k);
                }
            }
        }
    }

    fn unary(&mut self, op: Unary, a: Operand) -> Operand {
        if let Operand::Constant(x) = a {
            return Operand::Constant(op.apply(x));
        }
        let to = self.allocate();
        self.instructions.push(Instruction::Unary { op, a, to });
        self.release(&[a]);
        Operand::Register(to)
    }

    fn binary(&mut self, op: Binary, a: Operand, b: Operand) -> Operand {
        if let (Operand::Constant(x), Operand::Constant(z)) = (a, b) {
            return Operand::Constant(op.apply(x, z));
        }
        if let (Binary::Power, Operand::Constant(k)) = (op, b) {
            if k.fract() == 0.0 && k.abs() <= MOST_POWI {
                return self.unary(Unary::Powi(k as i32), a);
            }
        }
        let to = self.allocate();
        self.instructions.push(Instruction::Binary { op, a, b, to });
        self.release(&[a, b]);
        Operand::Register(to)
    }

    fn select(&mut self, condition: Operand, then: Operand, otherwise: Operand) -> Operand {
        if let Operand::Constant(c) = condition {
            if let (Operand::Constant(a), Operand::Constant(b)) = (then, otherwise) {
                return Operand::Constant(select(c, a, b));
            }
        }
        let to = self.allocate();
        self.instructions.push(Instruction::Select {
            condition,
            then,
            otherwise,
            to,
        });
        self.release(&[condition, then, otherwise]);
        Operand::Register(to)
    }

    fn emit(&mut self, node: &Node) -> Result<Operand, CompileError> {
        Ok(match &node.kind {
            NodeKind::Number(x) => Operand::Constant(*x),
            NodeKind::Name(name) => self.name(name, node.at)?,
            NodeKind::Unary(op, operand) => {
                let a = self.emit(operand)?;
                let op = match op {
                    UnaryOp::Negate => Unary::Negate,
                    UnaryOp::Not => Unary::Not,
                };
                self.unary(op, a)
            }
            NodeKind::Binary(op, left, right) => {
                let a = self.emit(left)?;
                let b = self.emit(right)?;
                self.binary(binary_op(*op), a, b)
            }
            NodeKind::Conditional(condition, then, otherwise) => {
                let c = self.emit(condition)?;
                let a = self.emit(then)?;
                let b = self.emit(otherwise)?;
                self.select(c, a, b)
            }
            NodeKind::Call(function, arguments) => self.call(function, arguments, node.at)?,
        })
    }

    fn name(&mut self, name: &str, at: usize) -> Result<Operand, CompileError> {
        if let Some(symbol) = self.symbols.get(name) {
            self.read.insert(name.to_string());
            return Ok(match *symbol {
                Symbol::Input(i) => Operand::Input(i),
                Symbol::Parameter(x) => Operand::Constant(x),
                Symbol::Defined(operand) => operand,
            });
        }
        if let Some((_, value)) = CONSTANTS.iter().find(|(c, _)| *c == name) {
            return Ok(Operand::Constant(*value));
        }
        if let Some(path) = self.below.get(name) {
            return Err(error(
                at,
                format!("{name:?} is defined below, at {path}: a formula reads only the inputs, the parameters and what is defined above it"),
            ));
        }
        if FUNCTIONS.iter().any(|(f, _)| *f == name) {
            return Err(error(at, format!("{name} is a function: write {name}(…)")));
        }
        Err(error(
            at,
            format!("unknown name {name:?}{}", self.suggestion(name)),
        ))
    }

    /// ` (did you mean …?)` when a known name is one or two edits away.
    fn suggestion(&self, name: &str) -> String {
        let known = (self.symbols.keys().map(String::as_str))
            .chain(self.below.keys().map(String::as_str))
            .chain(FUNCTIONS.iter().map(|(f, _)| *f))
            .chain(CONSTANTS.iter().map(|(c, _)| *c));
        let mut best: Option<(usize, &str)> = None;
        for candidate in known {
            let d = edit_distance(name, candidate);
            if d <= 2 && best.is_none_or(|(b, c)| (d, candidate) < (b, c)) {
                best = Some((d, candidate));
            }
        }
        best.map_or_else(String::new, |(_, c)| format!(" (did you mean {c}?)"))
    }

    fn call(
        &mut self,
        function: &str,
        arguments: &[Node],
        at: usize,
    ) -> Result<Operand, CompileError> {
        let Some(&(_, arity)) = FUNCTIONS.iter().find(|(f, _)| *f == function) else {
            let message = match self.symbols.get(function) {
                Some(_) => format!("{function} is a value, not a function"),
                None => format!("unknown function {function:?}{}", self.suggestion(function)),
            };
            return Err(error(at, message));
        };
        let n = arguments.len();
        match arity {
            Some(k) if n != k => {
                return Err(error(
                    at,
                    format!(
                        "{function} takes {k} argument{}, got {n}",
                        if k == 1 { "" } else { "s" }
                    ),
                ))
            }
            None if n < 2 => {
                return Err(error(
                    at,
                    format!("{function} takes two or more arguments, got {n}"),
                ))
            }
            _ => {}
        }
        let mut values = Vec::with_capacity(n);
        for argument in arguments {
            values.push(self.emit(argument)?);
        }
        Ok(match (function, values.as_slice()) {
            ("if", &[c, a, b]) => self.select(c, a, b),
            ("atan2", &[a, b]) => self.binary(Binary::Atan2, a, b),
            ("hypot", &[a, b]) => self.binary(Binary::Hypot, a, b),
            ("min" | "max", _) => {
                let op = if function == "min" {
                    Binary::Min
                } else {
                    Binary::Max
                };
                let mut value = values[0];
                for &next in &values[1..] {
                    value = self.binary(op, value, next);
                }
                value
            }
            (_, &[a]) => self.unary(unary_function(function), a),
            _ => return Err(error(at, format!("{function} cannot be applied here"))),
        })
    }
}

fn binary_op(op: BinaryOp) -> Binary {
    match op {
        BinaryOp::Add => Binary::Add,
        BinaryOp::Subtract => Binary::Subtract,
        BinaryOp::Multiply => Binary::Multiply,
        BinaryOp::Divide => Binary::Divide,
        BinaryOp::Power => Binary::Power,
        BinaryOp::Less => Binary::Less,
        BinaryOp::LessEqual => Binary::LessEqual,
        BinaryOp::Greater => Binary::Greater,
        BinaryOp::GreaterEqual => Binary::GreaterEqual,
        BinaryOp::Equal => Binary::Equal,
        BinaryOp::NotEqual => Binary::NotEqual,
        BinaryOp::And => Binary::And,
        BinaryOp::Or => Binary::Or,
    }
}

/// The operation of a function of one argument (the table's names of arity 1).
fn unary_function(name: &str) -> Unary {
    match name {
        "sin" => Unary::Sin,
        "cos" => Unary::Cos,
        "tan" => Unary::Tan,
        "asin" => Unary::Asin,
        "acos" => Unary::Acos,
        "atan" => Unary::Atan,
        "sqrt" => Unary::Sqrt,
        "exp" => Unary::Exp,
        "ln" => Unary::Ln,
        "log10" => Unary::Log10,
        "abs" => Unary::Abs,
        "floor" => Unary::Floor,
        _ => Unary::Ceil,
    }
}

/// Edit distance between two names: characters inserted, removed or replaced, and two
/// neighbours swapped, each one edit (optimal string alignment: `atna2` is one edit from
/// `atan2`, two from `atan`).
fn edit_distance(a: &str, b: &str) -> usize {
    let (a, b): (Vec<char>, Vec<char>) = (a.chars().collect(), b.chars().collect());
    let mut d = vec![vec![0usize; b.len() + 1]; a.len() + 1];
    for (i, row) in d.iter_mut().enumerate() {
        row[0] = i;
    }
    for (j, cell) in d[0].iter_mut().enumerate() {
        *cell = j;
    }
    for i in 1..=a.len() {
        for j in 1..=b.len() {
            let cost = usize::from(a[i - 1] != b[j - 1]);
            let mut best = (d[i - 1][j] + 1)
                .min(d[i][j - 1] + 1)
                .min(d[i - 1][j - 1] + cost);
            if i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1] {
                best = best.min(d[i - 2][j - 2] + 1);
            }
            d[i][j] = best;
        }
    }
    d[a.len()][b.len()]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::expression::parse::parse;

    fn compile(formula: &str) -> Result<Program, CompileError> {
        let mut compiler = Compiler::new(
            &["x".into(), "y".into()],
            &[("k".into(), 2.0)],
            HashMap::new(),
        );
        compiler.define("out", &parse(formula).unwrap(), true)?;
        Ok(compiler.finish())
    }

    #[test]
    fn constants_fold_and_whole_powers_multiply() {
        let program = compile("k * pi + 1").unwrap();
        assert!(program.instructions.is_empty());
        assert_eq!(
            program.outputs,
            [Operand::Constant(2.0 * std::f64::consts::PI + 1.0)]
        );
        let program = compile("x^2 + y^0.5").unwrap();
        assert!(matches!(
            program.instructions[0],
            Instruction::Unary {
                op: Unary::Powi(2),
                ..
            }
        ));
        assert!(matches!(
            program.instructions[1],
            Instruction::Binary {
                op: Binary::Power,
                ..
            }
        ));
    }

    #[test]
    fn registers_are_reused_once_read() {
        // Five operations, at most two values alive at once; an instruction's result
        // takes a register of its own while its operands are read: three registers.
        let program = compile("sin(x) + cos(y) * x - y").unwrap();
        assert_eq!(program.instructions.len(), 5);
        assert!(program.registers <= 3, "{}", program.registers);
        for instruction in &program.instructions {
            let (to, reads) = match *instruction {
                Instruction::Unary { a, to, .. } => (to, vec![a]),
                Instruction::Binary { a, b, to, .. } => (to, vec![a, b]),
                Instruction::Select {
                    condition,
                    then,
                    otherwise,
                    to,
                } => (to, vec![condition, then, otherwise]),
            };
            assert!(!reads.contains(&Operand::Register(to)));
        }
    }

    #[test]
    fn names_and_arities_are_checked() {
        let cases = [
            (
                "hypt(x, y)",
                1,
                "unknown function \"hypt\" (did you mean hypot?)",
            ),
            ("x + z", 5, "unknown name \"z\""),
            ("atan2(x)", 1, "atan2 takes 2 arguments, got 1"),
            ("min(x)", 1, "two or more"),
            ("sin + 1", 1, "sin is a function"),
            ("x(2)", 1, "a value, not a function"),
            ("if(x, y)", 1, "if takes 3 arguments"),
        ];
        for (formula, at, says) in cases {
            let err = compile(formula).unwrap_err();
            assert_eq!(err.at, at, "{formula}");
            assert!(err.message.contains(says), "{formula}: {}", err.message);
        }
    }

    #[test]
    fn edit_distances() {
        assert_eq!(edit_distance("hypt", "hypot"), 1);
        assert_eq!(edit_distance("", "abc"), 3);
        assert_eq!(edit_distance("kitten", "sitting"), 3);
        assert_eq!(edit_distance("atna2", "atan2"), 1);
        assert_eq!(edit_distance("atna2", "atan"), 2);
    }
}
