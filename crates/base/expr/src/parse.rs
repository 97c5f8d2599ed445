//! Lexer and recursive-descent parser.

use crate::{BinOp, Expr, ExprError, Func};

/// Deepest expression tree (and parser recursion) accepted, so that evaluating, printing or
/// dropping a parsed tree can never overflow the stack.
const MAX_DEPTH: usize = 400;

#[derive(Debug, Clone, Copy, PartialEq)]
enum Kind {
    Num(f64),
    Ident,
    Punct(char),
    End,
}

/// A token borrows its text from the input, so lexing allocates only the token list.
#[derive(Debug, Clone, Copy)]
struct Token<'a> {
    kind: Kind,
    /// 1-based character column.
    col: usize,
    text: &'a str,
}

/// Parses an expression.
///
/// Grammar, lowest to highest precedence (whitespace allowed anywhere):
///
/// ```text
/// sum     := product (('+' | '-') product)*
/// product := unary (('*' | '/') unary)*
/// unary   := ('-' | '+') unary | power
/// power   := atom ('^' unary)?            right-associative, so -2^2 = -(2^2)
/// atom    := number | name | func '(' sum (',' sum)* ')' | '(' sum ')'
/// number  := 1 | 2.5 | .5 | 1e-3 ...      name := [A-Za-z_][A-Za-z0-9_.]*
/// ```
///
/// `func` is one of sqrt sin cos tan asin acos atan atan2 exp log abs min max; `pi` is π.
/// Trees deeper than a few hundred levels are rejected.
/// Errors are one line and name the column and the input, e.g.
/// `expected ')' at column 6 in "sin(a"`.
pub fn parse(src: &str) -> Result<Expr, ExprError> {
    let mut parser = Parser {
        src,
        tokens: lex(src)?,
        pos: 0,
        nesting: 0,
    };
    let (expr, _) = parser.sum()?;
    let next = parser.peek();
    if next.kind != Kind::End {
        return Err(parser.unexpected());
    }
    Ok(expr)
}

/// Whether `name` can be used as a parameter's name: it reads back as exactly that symbol
/// (`[A-Za-z_][A-Za-z0-9_.]*`, as the lexer reads a name), and it is neither `pi` nor a
/// function's name.
pub fn is_symbol_name(name: &str) -> bool {
    let mut chars = name.chars();
    chars.next().is_some_and(starts_name)
        && chars.all(continues_name)
        && name != "pi"
        && Func::from_name(name).is_none()
}

fn starts_name(c: char) -> bool {
    c.is_ascii_alphabetic() || c == '_'
}

fn continues_name(c: char) -> bool {
    c.is_ascii_alphanumeric() || c == '_' || c == '.'
}

fn syntax(src: &str, message: String, column: usize) -> ExprError {
    ExprError::Syntax {
        message,
        column,
        input: src.to_string(),
    }
}

fn lex(src: &str) -> Result<Vec<Token<'_>>, ExprError> {
    // A byte scan: every token is ASCII, so only whitespace and errors need a whole
    // character (a model's build lexes hundreds of expressions; collecting the characters
    // and their offsets first cost a third of parsing). Columns count characters.
    let bytes = src.as_bytes();
    let is_digit = |i: usize| bytes.get(i).is_some_and(u8::is_ascii_digit);
    let mut tokens = Vec::new();
    // the byte at `i` is the character at 1-based column `col + 1`
    let (mut i, mut col) = (0, 0);
    while let Some(&b) = bytes.get(i) {
        let start = i;
        let kind = if !b.is_ascii() {
            // `i` is always at a character's first byte
            let c = src[i..].chars().next().unwrap_or_default();
            if c.is_whitespace() {
                i += c.len_utf8();
                col += 1;
                continue;
            }
            return Err(syntax(src, format!("unexpected character '{c}'"), col + 1));
        } else if char::from(b).is_whitespace() {
            i += 1;
            col += 1;
            continue;
        } else if b.is_ascii_digit() || (b == b'.' && is_digit(i + 1)) {
            while is_digit(i) {
                i += 1;
            }
            if bytes.get(i) == Some(&b'.') {
                i += 1;
                while is_digit(i) {
                    i += 1;
                }
            }
            if matches!(bytes.get(i), Some(b'e' | b'E')) {
                let j = if matches!(bytes.get(i + 1), Some(b'+' | b'-')) {
                    i + 2
                } else {
                    i + 1
                };
                if is_digit(j) {
                    i = j;
                    while is_digit(i) {
                        i += 1;
                    }
                }
            }
            match crate::number_literal(&src[start..i]) {
                Ok(x) => Kind::Num(x),
                Err(e) => return Err(syntax(src, e.to_string(), col + 1)),
            }
        } else if starts_name(char::from(b)) {
            i += 1;
            while bytes.get(i).is_some_and(|&b| continues_name(char::from(b))) {
                i += 1;
            }
            Kind::Ident
        } else if b"+-*/^(),".contains(&b) {
            i += 1;
            Kind::Punct(char::from(b))
        } else {
            return Err(syntax(
                src,
                format!("unexpected character '{}'", char::from(b)),
                col + 1,
            ));
        };
        tokens.push(Token {
            kind,
            col: col + 1,
            text: &src[start..i],
        });
        // a token is ASCII: one column per byte
        col += i - start;
    }
    tokens.push(Token {
        kind: Kind::End,
        col: col + 1,
        text: "",
    });
    Ok(tokens)
}

/// An expression and the depth of its tree.
type Parsed = Result<(Expr, usize), ExprError>;

struct Parser<'a> {
    src: &'a str,
    /// Always ends with a `Kind::End` token, which is never consumed.
    tokens: Vec<Token<'a>>,
    pos: usize,
    nesting: usize,
}

impl<'a> Parser<'a> {
    fn peek(&self) -> &Token<'a> {
        let last = self.tokens.len().saturating_sub(1);
        &self.tokens[self.pos.min(last)]
    }

    fn advance(&mut self) {
        if self.peek().kind != Kind::End {
            self.pos += 1;
        }
    }

    /// Consumes the next token if it is the punctuation `c`.
    fn eat(&mut self, c: char) -> bool {
        let found = self.peek().kind == Kind::Punct(c);
        if found {
            self.advance();
        }
        found
    }

    fn error_here(&self, message: String) -> ExprError {
        syntax(self.src, message, self.peek().col)
    }

    fn unexpected(&self) -> ExprError {
        let t = self.peek();
        match t.kind {
            Kind::End => self.error_here("unexpected end of input".into()),
            _ => self.error_here(format!("unexpected '{}'", t.text)),
        }
    }

    /// Wraps a new node, enforcing [`MAX_DEPTH`].
    fn node(&self, expr: Expr, depth: usize) -> Parsed {
        if depth > MAX_DEPTH {
            return Err(self.error_here("expression nested too deeply".into()));
        }
        Ok((expr, depth))
    }

    fn binary(&self, op: BinOp, (l, dl): (Expr, usize), (r, dr): (Expr, usize)) -> Parsed {
        self.node(Expr::Binary(op, Box::new(l), Box::new(r)), dl.max(dr) + 1)
    }

    fn sum(&mut self) -> Parsed {
        let mut left = self.product()?;
        loop {
            let op = match self.peek().kind {
                Kind::Punct('+') => BinOp::Add,
                Kind::Punct('-') => BinOp::Sub,
                _ => return Ok(left),
            };
            self.advance();
            let right = self.product()?;
            left = self.binary(op, left, right)?;
        }
    }

    fn product(&mut self) -> Parsed {
        let mut left = self.unary()?;
        loop {
            let op = match self.peek().kind {
                Kind::Punct('*') => BinOp::Mul,
                Kind::Punct('/') => BinOp::Div,
                _ => return Ok(left),
            };
            self.advance();
            let right = self.unary()?;
            left = self.binary(op, left, right)?;
        }
    }

    /// Every recursion of the parser passes through here, so this bounds its stack use.
    fn unary(&mut self) -> Parsed {
        self.nesting += 1;
        if self.nesting > MAX_DEPTH {
            return Err(self.error_here("expression nested too deeply".into()));
        }
        let result = if self.eat('-') {
            let (e, d) = self.unary()?;
            self.node(Expr::Neg(Box::new(e)), d + 1)
        } else if self.eat('+') {
            self.unary()
        } else {
            self.power()
        };
        self.nesting -= 1;
        result
    }

    fn power(&mut self) -> Parsed {
        let base = self.atom()?;
        if self.eat('^') {
            let exponent = self.unary()?;
            return self.binary(BinOp::Pow, base, exponent);
        }
        Ok(base)
    }

    fn atom(&mut self) -> Parsed {
        let token = *self.peek();
        match token.kind {
            Kind::Num(x) => {
                self.advance();
                Ok((Expr::Num(x), 1))
            }
            Kind::Ident => {
                self.advance();
                if self.eat('(') {
                    self.call(&token)
                } else if Func::from_name(token.text).is_some() {
                    Err(self.error_here(format!("expected '(' after function '{}'", token.text)))
                } else {
                    Ok((Expr::Sym(token.text.to_string()), 1))
                }
            }
            Kind::Punct('(') => {
                self.advance();
                let inner = self.sum()?;
                if !self.eat(')') {
                    return Err(self.error_here("expected ')'".into()));
                }
                Ok(inner)
            }
            Kind::End => Err(self.error_here("expected an expression".into())),
            Kind::Punct(_) => Err(self.unexpected()),
        }
    }

    /// Parses the arguments of a call; the name and `(` are already consumed.
    fn call(&mut self, name: &Token<'a>) -> Parsed {
        let func = Func::from_name(name.text).ok_or_else(|| ExprError::UnknownFunction {
            name: name.text.to_string(),
            column: name.col,
            input: self.src.to_string(),
        })?;
        let mut args = Vec::new();
        let mut depth = 0;
        if !self.eat(')') {
            loop {
                let (arg, d) = self.sum()?;
                args.push(arg);
                depth = depth.max(d);
                if self.eat(')') {
                    break;
                }
                if !self.eat(',') {
                    return Err(self.error_here("expected ')'".into()));
                }
            }
        }
        if !func.accepts(args.len()) {
            return Err(ExprError::WrongArity {
                func,
                got: args.len(),
            });
        }
        self.node(Expr::Call(func, args), depth + 1)
    }
}
