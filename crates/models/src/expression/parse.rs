//! The formulas of an `expression` model, read into a tree: a lexer and a Pratt
//! (precedence-climbing) parser written here rather than taken from a crate, because the
//! grammar is small, the messages must name the character a mistake is at, and the limits
//! (length, nesting) must hold against any input without a panic or a stack overflow
//! (a property test feeds it arbitrary text).
//!
//! Grammar, loosest binding first (every binary operator left-associative but `^`):
//!
//! ```text
//! formula     := conditional
//! conditional := or ("?" conditional ":" conditional)?
//! or          := and ("||" and)*
//! and         := compare ("&&" compare)*
//! compare     := sum (("<" | "<=" | ">" | ">=" | "==" | "!=") sum)?     (not chained)
//! sum         := product (("+" | "-") product)*
//! product     := unary (("*" | "/") unary)*
//! unary       := ("-" | "+" | "!") unary | power
//! power       := primary (("^" | "**") unary)?                          (right to left)
//! primary     := number | name | name "(" formula ("," formula)* ")" | "(" formula ")"
//! ```
//!
//! So `-x^2` is −(x²) and `2^-1` is 0.5, as in mathematics (and ExprTk, Excel aside).
//! Positions are counted in characters from 1.

/// Most characters a formula may have (a longer one is split with `let`).
pub const MOST_CHARACTERS: usize = 10_000;

/// Deepest nesting a formula may have: parentheses, a call's arguments, the branches of
/// `?`, a prefix operator and an exponent each open a level.
pub const MOST_DEPTH: usize = 100;

/// A node of the formula's tree and the character it starts at.
#[derive(Debug, Clone, PartialEq)]
pub struct Node {
    /// Position of its first character, from 1.
    pub at: usize,
    /// What it is.
    pub kind: NodeKind,
}

/// The kinds of node.
#[derive(Debug, Clone, PartialEq)]
pub enum NodeKind {
    /// A number as written.
    Number(f64),
    /// A name: an input, a parameter, an earlier `let` or output, or `pi`.
    Name(String),
    /// A function applied to its arguments.
    Call(String, Vec<Node>),
    /// A prefix operator.
    Unary(UnaryOp, Box<Node>),
    /// A binary operator.
    Binary(BinaryOp, Box<Node>, Box<Node>),
    /// `condition ? then : otherwise`.
    Conditional(Box<Node>, Box<Node>, Box<Node>),
}

/// Prefix operators.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum UnaryOp {
    /// −x.
    Negate,
    /// !x: 1 where x is 0, else 0.
    Not,
}

/// Binary operators.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BinaryOp {
    /// a + b.
    Add,
    /// a − b.
    Subtract,
    /// a·b.
    Multiply,
    /// a / b.
    Divide,
    /// a^b.
    Power,
    /// a < b (1 or 0).
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
    /// Both non-zero.
    And,
    /// Either non-zero.
    Or,
}

/// A mistake in a formula and the character it is at.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SyntaxError {
    /// Position of the character, from 1.
    pub at: usize,
    /// What is wrong.
    pub message: String,
}

impl SyntaxError {
    fn new(at: usize, message: impl Into<String>) -> Self {
        SyntaxError {
            at,
            message: message.into(),
        }
    }
}

/// A token and its position.
#[derive(Debug, Clone, PartialEq)]
struct Token {
    at: usize,
    kind: TokenKind,
}

#[derive(Debug, Clone, PartialEq)]
enum TokenKind {
    Number(f64),
    Name(String),
    /// An operator or punctuation, as written (`<=`, `(`, `**`).
    Symbol(&'static str),
    End,
}

/// Operators and punctuation, longest first so `<=` is not read as `<`.
const SYMBOLS: &[&str] = &[
    "**", "<=", ">=", "==", "!=", "&&", "||", "+", "-", "*", "/", "^", "(", ")", ",", "?", ":",
    "<", ">", "!",
];

/// Parses one formula.
pub fn parse(text: &str) -> Result<Node, SyntaxError> {
    let length = text.chars().count();
    if length > MOST_CHARACTERS {
        return Err(SyntaxError::new(
            MOST_CHARACTERS + 1,
            format!(
                "the formula has {length} characters; at most {MOST_CHARACTERS} (name parts of it with `let`)"
            ),
        ));
    }
    let tokens = lex(text)?;
    let mut parser = Parser {
        tokens,
        next: 0,
        depth: 0,
    };
    if parser.peek().kind == TokenKind::End {
        return Err(SyntaxError::new(1, "the formula is empty"));
    }
    let node = parser.conditional()?;
    let token = parser.peek();
    match &token.kind {
        TokenKind::End => Ok(node),
        TokenKind::Symbol(")") => Err(SyntaxError::new(token.at, "this ')' closes no '('")),
        other => Err(SyntaxError::new(
            token.at,
            format!("expected an operator, got {}", describe(other)),
        )),
    }
}

/// The formula's tokens, ending with [`TokenKind::End`].
fn lex(text: &str) -> Result<Vec<Token>, SyntaxError> {
    let chars: Vec<char> = text.chars().collect();
    let mut tokens = Vec::new();
    let mut i = 0;
    while i < chars.len() {
        let c = chars[i];
        let at = i + 1;
        if c.is_whitespace() {
            i += 1;
        } else if c.is_ascii_digit()
            || (c == '.' && chars.get(i + 1).is_some_and(char::is_ascii_digit))
        {
            let (value, end) = number(&chars, i)?;
            tokens.push(Token {
                at,
                kind: TokenKind::Number(value),
            });
            i = end;
        } else if c.is_ascii_alphabetic() || c == '_' {
            let end = (i..chars.len())
                .find(|&k| !(chars[k].is_ascii_alphanumeric() || chars[k] == '_'))
                .unwrap_or(chars.len());
            if let Some(&next) = chars
                .get(end)
                .filter(|c| !c.is_ascii() && c.is_alphanumeric())
            {
                return Err(non_ascii(end + 1, next));
            }
            tokens.push(Token {
                at,
                kind: TokenKind::Name(chars[i..end].iter().collect()),
            });
            i = end;
        } else if let Some(symbol) = SYMBOLS.iter().find(|s| {
            s.chars()
                .enumerate()
                .all(|(k, sc)| chars.get(i + k) == Some(&sc))
        }) {
            tokens.push(Token {
                at,
                kind: TokenKind::Symbol(symbol),
            });
            i += symbol.len();
        } else {
            return Err(match c {
                '=' => SyntaxError::new(at, "'=' alone is no operator: write '==' to compare"),
                '&' => SyntaxError::new(at, "'&' alone is no operator: write '&&'"),
                '|' => SyntaxError::new(at, "'|' alone is no operator: write '||', or abs(x)"),
                c if !c.is_ascii() && c.is_alphanumeric() => non_ascii(at, c),
                c => SyntaxError::new(
                    at,
                    format!("unexpected character {c:?} (U+{:04X})", c as u32),
                ),
            });
        }
    }
    tokens.push(Token {
        at: chars.len() + 1,
        kind: TokenKind::End,
    });
    Ok(tokens)
}

fn non_ascii(at: usize, c: char) -> SyntaxError {
    SyntaxError::new(
        at,
        format!(
            "{c:?} (U+{:04X}) cannot be in a name: names are ASCII letters, digits and '_'",
            c as u32
        ),
    )
}

/// The number starting at `chars[start]` and the index after it: digits, an optional
/// fraction, an optional exponent (`1.5e-3`, `.5`, `2E6`).
fn number(chars: &[char], start: usize) -> Result<(f64, usize), SyntaxError> {
    let digits = |from: usize| {
        (from..chars.len())
            .find(|&k| !chars[k].is_ascii_digit())
            .unwrap_or(chars.len())
    };
    let mut end = digits(start);
    if chars.get(end) == Some(&'.') {
        end = digits(end + 1);
    }
    if matches!(chars.get(end), Some('e' | 'E')) {
        let sign = usize::from(matches!(chars.get(end + 1), Some('+' | '-')));
        if chars.get(end + 1 + sign).is_some_and(char::is_ascii_digit) {
            end = digits(end + 1 + sign);
        }
    }
    let written: String = chars[start..end].iter().collect();
    match written.parse::<f64>() {
        Ok(value) if value.is_finite() => Ok((value, end)),
        _ => Err(SyntaxError::new(
            start + 1,
            format!("{written} is not a finite number"),
        )),
    }
}

fn describe(kind: &TokenKind) -> String {
    match kind {
        TokenKind::Number(_) => "a number".into(),
        TokenKind::Name(name) => format!("the name {name:?}"),
        TokenKind::Symbol(symbol) => format!("'{symbol}'"),
        TokenKind::End => "the end of the formula".into(),
    }
}

struct Parser {
    tokens: Vec<Token>,
    next: usize,
    depth: usize,
}

impl Parser {
    fn peek(&self) -> &Token {
        &self.tokens[self.next]
    }

    fn advance(&mut self) -> Token {
        let token = self.tokens[self.next].clone();
        if token.kind != TokenKind::End {
            self.next += 1;
        }
        token
    }

    /// Whether the next token is `symbol` (then taken).
    fn take(&mut self, symbol: &str) -> bool {
        let found = matches!(self.peek().kind, TokenKind::Symbol(s) if s == symbol);
        if found {
            self.next += 1;
        }
        found
    }

    fn expect(&mut self, symbol: &str, context: &str) -> Result<(), SyntaxError> {
        if self.take(symbol) {
            return Ok(());
        }
        let token = self.peek();
        Err(SyntaxError::new(
            token.at,
            format!(
                "expected '{symbol}' {context}, got {}",
                describe(&token.kind)
            ),
        ))
    }

    /// One level deeper; refused past [`MOST_DEPTH`] levels below the formula itself
    /// (which is the first call).
    fn enter(&mut self) -> Result<(), SyntaxError> {
        self.depth += 1;
        if self.depth > MOST_DEPTH + 1 {
            return Err(SyntaxError::new(
                self.peek().at,
                format!("the formula nests deeper than {MOST_DEPTH} levels"),
            ));
        }
        Ok(())
    }

    fn conditional(&mut self) -> Result<Node, SyntaxError> {
        self.enter()?;
        let condition = self.binary(0)?;
        let node = if self.take("?") {
            let then = self.conditional()?;
            self.expect(":", "between the two branches of '?'")?;
            let otherwise = self.conditional()?;
            Node {
                at: condition.at,
                kind: NodeKind::Conditional(
                    Box::new(condition),
                    Box::new(then),
                    Box::new(otherwise),
                ),
            }
        } else {
            condition
        };
        self.depth -= 1;
        Ok(node)
    }

    /// Binary operators binding at least as tight as `level` (0: `||` … 4: `*` `/`).
    fn binary(&mut self, level: usize) -> Result<Node, SyntaxError> {
        const LEVELS: &[&[(&str, BinaryOp)]] = &[
            &[("||", BinaryOp::Or)],
            &[("&&", BinaryOp::And)],
            &[
                ("<=", BinaryOp::LessEqual),
                (">=", BinaryOp::GreaterEqual),
                ("==", BinaryOp::Equal),
                ("!=", BinaryOp::NotEqual),
                ("<", BinaryOp::Less),
                (">", BinaryOp::Greater),
            ],
            &[("+", BinaryOp::Add), ("-", BinaryOp::Subtract)],
            &[("*", BinaryOp::Multiply), ("/", BinaryOp::Divide)],
        ];
        const COMPARE: usize = 2;
        if level == LEVELS.len() {
            return self.unary();
        }
        let mut left = self.binary(level + 1)?;
        let mut compared = false;
        loop {
            let found = LEVELS[level].iter().find(
                |(symbol, _)| matches!(self.peek().kind, TokenKind::Symbol(s) if s == *symbol),
            );
            let Some(&(_, op)) = found else { break };
            let at = self.advance().at;
            if level == COMPARE && compared {
                return Err(SyntaxError::new(
                    at,
                    "comparisons do not chain: write a < b && b < c",
                ));
            }
            compared = true;
            let right = self.binary(level + 1)?;
            left = Node {
                at: left.at,
                kind: NodeKind::Binary(op, Box::new(left), Box::new(right)),
            };
        }
        Ok(left)
    }

    fn unary(&mut self) -> Result<Node, SyntaxError> {
        let at = self.peek().at;
        let op = match self.peek().kind {
            TokenKind::Symbol("-") => Some(UnaryOp::Negate),
            TokenKind::Symbol("!") => Some(UnaryOp::Not),
            TokenKind::Symbol("+") => None,
            _ => return self.power(),
        };
        self.advance();
        self.enter()?;
        let operand = self.unary()?;
        self.depth -= 1;
        Ok(match op {
            Some(op) => Node {
                at,
                kind: NodeKind::Unary(op, Box::new(operand)),
            },
            None => operand,
        })
    }

    fn power(&mut self) -> Result<Node, SyntaxError> {
        let base = self.primary()?;
        if self.take("^") || self.take("**") {
            self.enter()?;
            let exponent = self.unary()?;
            self.depth -= 1;
            return Ok(Node {
                at: base.at,
                kind: NodeKind::Binary(BinaryOp::Power, Box::new(base), Box::new(exponent)),
            });
        }
        Ok(base)
    }

    fn primary(&mut self) -> Result<Node, SyntaxError> {
        let token = self.advance();
        let node = match token.kind {
            TokenKind::Number(value) => Node {
                at: token.at,
                kind: NodeKind::Number(value),
            },
            TokenKind::Name(name) if self.take("(") => {
                let mut arguments = Vec::new();
                if !self.take(")") {
                    loop {
                        arguments.push(self.conditional()?);
                        if self.take(")") {
                            break;
                        }
                        self.expect(",", &format!("or ')' in the arguments of {name}"))?;
                    }
                }
                Node {
                    at: token.at,
                    kind: NodeKind::Call(name, arguments),
                }
            }
            TokenKind::Name(name) => Node {
                at: token.at,
                kind: NodeKind::Name(name),
            },
            TokenKind::Symbol("(") => {
                let inner = self.conditional()?;
                let close = self.peek().at;
                if !self.take(")") {
                    return Err(SyntaxError::new(
                        close,
                        format!(
                            "the '(' at character {} is not closed: expected ')', got {}",
                            token.at,
                            describe(&self.peek().kind)
                        ),
                    ));
                }
                inner
            }
            other => {
                return Err(SyntaxError::new(
                    token.at,
                    format!("expected a number, a name or '(', got {}", describe(&other)),
                ))
            }
        };
        Ok(node)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The tree written back with every operation parenthesised.
    fn shown(node: &Node) -> String {
        match &node.kind {
            NodeKind::Number(x) => format!("{x}"),
            NodeKind::Name(name) => name.clone(),
            NodeKind::Call(name, args) => {
                let args: Vec<String> = args.iter().map(shown).collect();
                format!("{name}({})", args.join(", "))
            }
            NodeKind::Unary(UnaryOp::Negate, x) => format!("(-{})", shown(x)),
            NodeKind::Unary(UnaryOp::Not, x) => format!("(!{})", shown(x)),
            NodeKind::Binary(op, a, b) => format!("({} {op:?} {})", shown(a), shown(b)),
            NodeKind::Conditional(c, a, b) => {
                format!("({} ? {} : {})", shown(c), shown(a), shown(b))
            }
        }
    }

    #[test]
    fn precedence_and_associativity() {
        let cases = [
            ("1 + 2 * 3", "(1 Add (2 Multiply 3))"),
            ("1 - 2 - 3", "((1 Subtract 2) Subtract 3)"),
            ("8 / 4 / 2", "((8 Divide 4) Divide 2)"),
            ("-x^2", "(-(x Power 2))"),
            ("2^3^2", "(2 Power (3 Power 2))"),
            ("2**-1", "(2 Power (-1))"),
            (
                "a < b && c >= d || !e",
                "(((a Less b) And (c GreaterEqual d)) Or (!e))",
            ),
            ("c ? a : d ? b : e", "(c ? a : (d ? b : e))"),
            ("hypot(x, y) - 1.5e-3", "(hypot(x, y) Subtract 0.0015)"),
            ("(a + b) * .5", "((a Add b) Multiply 0.5)"),
            ("f()", "f()"),
        ];
        for (text, tree) in cases {
            assert_eq!(shown(&parse(text).unwrap()), tree, "{text}");
        }
    }

    #[test]
    fn mistakes_name_their_character() {
        let cases = [
            ("", 1, "empty"),
            ("   ", 1, "empty"),
            ("(a + b", 7, "not closed"),
            ("a + b)", 6, "closes no"),
            ("a +", 4, "expected a number"),
            ("a b", 3, "expected an operator"),
            ("a = b", 3, "'=='"),
            ("a < b < c", 7, "do not chain"),
            ("f(a b)", 5, "expected ','"),
            ("x$", 2, "unexpected character"),
            ("größe", 3, "cannot be in a name"),
            ("1e999", 1, "not a finite number"),
            ("c ? a", 6, "expected ':'"),
        ];
        for (text, at, says) in cases {
            let err = parse(text).unwrap_err();
            assert_eq!(err.at, at, "{text}: {}", err.message);
            assert!(err.message.contains(says), "{text}: {}", err.message);
        }
    }

    #[test]
    fn limits_hold_without_overflowing_the_stack() {
        let deep = format!("{}x{}", "(".repeat(4_000), ")".repeat(4_000));
        let err = parse(&deep).unwrap_err();
        assert!(err.message.contains("nests deeper"), "{}", err.message);
        // The first character inside the 101st '(' is one level too deep.
        assert_eq!(err.at, MOST_DEPTH + 2);
        let negations = format!("{}x", "-".repeat(9_000));
        assert!(parse(&negations)
            .unwrap_err()
            .message
            .contains("nests deeper"));
        let exponents = format!("x{}", "^x".repeat(4_000));
        assert!(parse(&exponents)
            .unwrap_err()
            .message
            .contains("nests deeper"));
        let branches = format!("{}x", "x ? x : ".repeat(1_000));
        assert!(parse(&branches)
            .unwrap_err()
            .message
            .contains("nests deeper"));
        // Ten thousand levels do not fit in the length a formula may have.
        let deepest = format!("{}x{}", "(".repeat(10_000), ")".repeat(10_000));
        assert_eq!(parse(&deepest).unwrap_err().at, MOST_CHARACTERS + 1);
        let long = "x + ".repeat(300_000) + "x";
        let err = parse(&long).unwrap_err();
        assert_eq!(err.at, MOST_CHARACTERS + 1);
        // Just inside both limits.
        let nested = format!("{}x{}", "(".repeat(MOST_DEPTH), ")".repeat(MOST_DEPTH));
        assert!(parse(&nested).is_ok());
    }
}
