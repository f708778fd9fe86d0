//! Compiled expressions: a flat program of elementwise operations evaluated over whole
//! batches of points at once.
//!
//! A text expression is compiled once (read by `model::syntax`, see `model::compile`)
//! into a list of instructions in static single assignment form, with
//! registers reused once a value is dead. Evaluation runs one pass per instruction over a
//! block of [`BLOCK`] points (structure of arrays), as NumPy runs one pass per operation over
//! an array: the arithmetic operators are plain loops the compiler vectorises, and functions
//! (`sin`, `cos`, …) are called per element without any interpretation per point; `exp`, `ln`,
//! `atan` and `sqrt` are passes that vectorise ([`crate::linalg::elementary`]), and so is `abs`.
//!
//! The per-point value of an expression runs the same operations on scalars, instruction by
//! instruction (without a pass's dispatch per instruction), so the batch and the point-wise
//! results are equal to the last bit (tested in `model::compile`). Against an interpreter of the
//! same operations in the same order (exmex, in the tests) the program differs only where it strength-reduces an integer power `x^k` (0 ≤ k ≤ 4) to
//! multiplications, which is within 2 ulp of `libm::pow` (tested here and, on whole
//! expressions, in `model::compile`).

use alloc::vec::Vec;

/// Points per pass: a register holds one block (2 KiB), so a program's registers stay in the
/// first-level cache.
pub(crate) const BLOCK: usize = 256;

/// A real function of one real variable.
pub(crate) type UnaryFn = fn(f64) -> f64;
/// A real function of two real variables.
pub(crate) type BinaryFn = fn(f64, f64) -> f64;

/// Where an instruction reads one of its arguments.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Operand {
    /// State component j of the point.
    Var(usize),
    /// A constant.
    Const(f64),
    /// A register.
    Reg(usize),
}

/// An elementwise operation.
#[derive(Clone, Copy, Debug)]
pub(crate) enum Operation {
    /// `-a`.
    Neg(Operand),
    /// `f(a)`.
    Unary(UnaryFn, Operand),
    /// `e^a` ([`crate::linalg::elementary::exp`], a pass that vectorises).
    Exp(Operand),
    /// `ln a` ([`crate::linalg::elementary::ln`], a pass that vectorises).
    Ln(Operand),
    /// `|a|` (a pass that vectorises).
    Abs(Operand),
    /// `atan a` ([`crate::linalg::elementary::atan`], a pass that vectorises).
    Atan(Operand),
    /// `√a` (a pass that vectorises where the processor has the instruction).
    Sqrt(Operand),
    /// `a + b`.
    Add(Operand, Operand),
    /// `a - b`.
    Sub(Operand, Operand),
    /// `a * b`.
    Mul(Operand, Operand),
    /// `a / b`.
    Div(Operand, Operand),
    /// `a^k` for a small integer k, by repeated multiplication.
    PowI(Operand, i32),
    /// `f(a, b)` (`^` with a non-integer exponent, `atan2`, `min`, `max`).
    Binary(BinaryFn, Operand, Operand),
}

impl Operation {
    /// The operands read.
    pub(crate) fn operands(&self) -> [Option<Operand>; 2] {
        match *self {
            Operation::Neg(a)
            | Operation::Unary(_, a)
            | Operation::Exp(a)
            | Operation::Ln(a)
            | Operation::Abs(a)
            | Operation::Atan(a)
            | Operation::Sqrt(a)
            | Operation::PowI(a, _) => [Some(a), None],
            Operation::Add(a, b)
            | Operation::Sub(a, b)
            | Operation::Mul(a, b)
            | Operation::Div(a, b)
            | Operation::Binary(_, a, b) => [Some(a), Some(b)],
        }
    }

    /// The operation on scalars: the value [`apply`]'s pass writes for `a` (and `b`).
    #[inline(always)]
    fn at(&self, a: f64, b: f64) -> f64 {
        match *self {
            Operation::Neg(_) => -a,
            Operation::Unary(f, _) => f(a),
            Operation::Exp(_) => crate::linalg::elementary::exp(a),
            Operation::Ln(_) => crate::linalg::elementary::ln(a),
            Operation::Abs(_) => libm::fabs(a),
            Operation::Atan(_) => atan_out_of_line(a),
            Operation::Sqrt(_) => crate::linalg::elementary::sqrt(a),
            Operation::Add(..) => a + b,
            Operation::Sub(..) => a - b,
            Operation::Mul(..) => a * b,
            Operation::Div(..) => a / b,
            Operation::PowI(_, k) => pow_int(a, k),
            Operation::Binary(f, ..) => f(a, b),
        }
    }

    fn map_operands(self, f: impl Fn(Operand) -> Operand) -> Operation {
        match self {
            Operation::Neg(a) => Operation::Neg(f(a)),
            Operation::Unary(g, a) => Operation::Unary(g, f(a)),
            Operation::Exp(a) => Operation::Exp(f(a)),
            Operation::Ln(a) => Operation::Ln(f(a)),
            Operation::Abs(a) => Operation::Abs(f(a)),
            Operation::Atan(a) => Operation::Atan(f(a)),
            Operation::Sqrt(a) => Operation::Sqrt(f(a)),
            Operation::PowI(a, k) => Operation::PowI(f(a), k),
            Operation::Add(a, b) => Operation::Add(f(a), f(b)),
            Operation::Sub(a, b) => Operation::Sub(f(a), f(b)),
            Operation::Mul(a, b) => Operation::Mul(f(a), f(b)),
            Operation::Div(a, b) => Operation::Div(f(a), f(b)),
            Operation::Binary(g, a, b) => Operation::Binary(g, f(a), f(b)),
        }
    }
}

/// Largest k of `x^k` that [`Operation::PowI`] computes by multiplication.
pub(crate) const MAX_POWI: i32 = 4;

/// `a^k` by repeated multiplication (0 ≤ k ≤ [`MAX_POWI`]).
#[inline(always)]
pub(crate) fn pow_int(a: f64, k: i32) -> f64 {
    match k {
        0 => 1.0,
        1 => a,
        2 => a * a,
        3 => a * a * a,
        _ => {
            let s = a * a;
            s * s
        }
    }
}

/// One instruction: `registers[dst] = operation`.
#[derive(Clone, Copy, Debug)]
struct Instruction {
    dst: usize,
    operation: Operation,
}

/// A compiled scalar function of the state: instructions over registers and the operands
/// that hold the results — one for an expression, several for a function and its partial
/// derivatives computed together ([`Program::eval_all`]), sharing what they have in common.
#[derive(Clone, Debug)]
pub(crate) struct Program {
    code: Vec<Instruction>,
    registers: usize,
    /// The results; a batch ([`Program::run`]) and [`Program::eval`] give the first.
    results: Vec<Operand>,
}

impl Program {
    /// A program from operations in single assignment form (`ssa[i]` defines value i, read as
    /// `Operand::Reg(i)` by later operations) and the operands holding the results. Registers
    /// are reused once a value has been read for the last time.
    pub(crate) fn from_ssa(ssa: &[Operation], results: &[Operand]) -> Program {
        let mut last_use = alloc::vec![usize::MAX; ssa.len()];
        for (i, op) in ssa.iter().enumerate() {
            for r in op.operands().into_iter().flatten() {
                if let Operand::Reg(v) = r {
                    last_use[v] = i;
                }
            }
        }
        for result in results {
            if let Operand::Reg(v) = *result {
                last_use[v] = usize::MAX - 1;
            }
        }
        let mut physical = alloc::vec![0usize; ssa.len()];
        let mut free: Vec<usize> = Vec::new();
        let mut registers = 0;
        let mut code = Vec::with_capacity(ssa.len());
        for (i, op) in ssa.iter().enumerate() {
            if last_use[i] == usize::MAX {
                continue; // never read: dead code
            }
            // The destination never aliases an operand of the same instruction.
            let dst = free.pop().unwrap_or_else(|| {
                registers += 1;
                registers - 1
            });
            physical[i] = dst;
            let operation = op.map_operands(|o| match o {
                Operand::Reg(v) => Operand::Reg(physical[v]),
                other => other,
            });
            code.push(Instruction { dst, operation });
            for r in op.operands().into_iter().flatten() {
                if let Operand::Reg(v) = r {
                    if last_use[v] == i && !free.contains(&physical[v]) {
                        free.push(physical[v]);
                    }
                }
            }
        }
        let results = results
            .iter()
            .map(|result| match *result {
                Operand::Reg(v) => Operand::Reg(physical[v]),
                other => other,
            })
            .collect();
        Program {
            code,
            registers,
            results,
        }
    }

    /// Number of registers, each [`BLOCK`] values long during a batch evaluation.
    pub(crate) fn registers(&self) -> usize {
        self.registers
    }

    /// Number of instructions.
    #[cfg(test)]
    pub(crate) fn len(&self) -> usize {
        self.code.len()
    }

    /// True for a constant or a bare variable (no instruction).
    #[cfg(test)]
    pub(crate) fn is_empty(&self) -> bool {
        self.code.is_empty()
    }

    /// The constant value, when the program is one.
    #[cfg(test)]
    pub(crate) fn constant(&self) -> Option<f64> {
        match self.results[0] {
            Operand::Const(c) => Some(c),
            _ => None,
        }
    }

    /// Evaluates at `lanes` points: `inputs[j]` holds component j of every point (at least
    /// `lanes` values each), `registers` at least `self.registers() * lanes` values; the value
    /// (the first result) at point p is written to `out[p]`.
    pub(crate) fn run(
        &self,
        inputs: &[&[f64]],
        lanes: usize,
        registers: &mut [f64],
        out: &mut [f64],
    ) {
        run_code(&self.code, inputs, lanes, registers);
        match self.results[0] {
            Operand::Const(c) => out[..lanes].fill(c),
            Operand::Var(j) => out[..lanes].copy_from_slice(&inputs[j][..lanes]),
            Operand::Reg(r) => out[..lanes].copy_from_slice(&registers[r * lanes..(r + 1) * lanes]),
        }
    }

    /// The program with inputs `first..` fixed to `values` (a driven model's time and inputs,
    /// frozen for one step): every operation on those and on constants alone is computed once
    /// here, with the function evaluation would apply (the same bits), and the rest reads the
    /// results as constants — so `cos(1.2*t)` costs one cosine per step, not one per point.
    /// The result reads inputs `0..first` only.
    pub(crate) fn with_inputs_fixed(&self, first: usize, values: &[f64]) -> Program {
        let mut known: Vec<Option<f64>> = alloc::vec![None; self.registers];
        let fixed = |o: Operand, known: &[Option<f64>]| match o {
            Operand::Var(j) if j >= first => Operand::Const(values[j - first]),
            Operand::Reg(r) => known[r].map_or(o, Operand::Const),
            o => o,
        };
        let mut code = Vec::with_capacity(self.code.len());
        for ins in &self.code {
            let operation = ins.operation.map_operands(|o| fixed(o, &known));
            let [a, b] = operation.operands();
            let constant = |o: Option<Operand>| match o {
                None => Some(0.0),
                Some(Operand::Const(c)) => Some(c),
                Some(_) => None,
            };
            match (constant(a), constant(b)) {
                (Some(x), Some(y)) => known[ins.dst] = Some(operation.at(x, y)),
                _ => {
                    known[ins.dst] = None;
                    code.push(Instruction {
                        dst: ins.dst,
                        operation,
                    });
                }
            }
        }
        Program {
            code,
            registers: self.registers,
            results: self.results.iter().map(|&r| fixed(r, &known)).collect(),
        }
    }

    /// The value at one point `x`, instruction by instruction on scalars ([`Operation::at`]:
    /// the same operations as a batch's passes, so the same bits), registers on the stack up
    /// to 32.
    pub(crate) fn eval(&self, x: &[f64]) -> f64 {
        self.at_point(x, |registers| read(self.results[0], x, registers))
    }

    /// Every result at one point `x` (as [`Program::eval`]), result r handed to `put(r, value)`:
    /// a function and its derivatives in one pass over the instructions they share.
    pub(crate) fn eval_all(&self, x: &[f64], mut put: impl FnMut(usize, f64)) {
        self.at_point(x, |registers| {
            for (r, &o) in self.results.iter().enumerate() {
                put(r, read(o, x, registers));
            }
        })
    }

    /// Runs the instructions at `x` on scalars, then hands the registers to `results`.
    #[inline(always)]
    fn at_point<R>(&self, x: &[f64], results: impl FnOnce(&[f64]) -> R) -> R {
        let mut on_stack = [0.0; 32];
        let mut on_heap = Vec::new();
        let registers = if self.registers <= on_stack.len() {
            &mut on_stack[..]
        } else {
            on_heap.resize(self.registers, 0.0);
            &mut on_heap[..]
        };
        for ins in &self.code {
            let [a, b] = ins.operation.operands();
            let a = a.map_or(0.0, |o| read(o, x, registers));
            let b = b.map_or(0.0, |o| read(o, x, registers));
            registers[ins.dst] = ins.operation.at(a, b);
        }
        results(registers)
    }
}

/// The value of operand `o` at point `x` with scalar `registers`.
#[inline(always)]
fn read(o: Operand, x: &[f64], registers: &[f64]) -> f64 {
    match o {
        Operand::Var(j) => x[j],
        Operand::Const(c) => c,
        Operand::Reg(r) => registers[r],
    }
}

/// [`crate::linalg::elementary::atan`] as a call, for the scalar interpreter: inlined there,
/// its two divisions and selects crowd the loop that every instruction runs through (the same
/// operations, so the same bits as the batch pass's inlined copy).
#[inline(never)]
fn atan_out_of_line(x: f64) -> f64 {
    crate::linalg::elementary::atan(x)
}

/// Most state components whose slices a batch evaluation keeps on the stack (more are
/// gathered into a vector).
pub(crate) const MAX_INPUTS: usize = 64;

/// An argument of an elementwise operation: a block of values or a constant.
#[derive(Clone, Copy)]
enum Arg<'a> {
    Slice(&'a [f64]),
    Scalar(f64),
}

/// The destination block and the argument blocks of one instruction. Two operands in the same
/// register are one shared borrow; the destination never is an operand (see
/// [`Program::from_ssa`]).
fn operands<'a>(
    registers: &'a mut [f64],
    lanes: usize,
    dst: usize,
    operation: &Operation,
    inputs: &[&'a [f64]],
) -> (&'a mut [f64], Arg<'a>, Arg<'a>) {
    let [a, b] = operation.operands();
    let block = |r: usize| r * lanes..(r + 1) * lanes;
    let reg = |o: Option<Operand>| match o {
        Some(Operand::Reg(r)) => Some(r),
        _ => None,
    };
    let other = |o: Option<Operand>| match o {
        Some(Operand::Var(j)) => Arg::Slice(&inputs[j][..lanes]),
        Some(Operand::Const(c)) => Arg::Scalar(c),
        _ => Arg::Scalar(0.0),
    };
    match (reg(a), reg(b)) {
        (None, None) => (&mut registers[block(dst)], other(a), other(b)),
        (Some(ra), None) => {
            let [d, s] = registers
                .get_disjoint_mut([block(dst), block(ra)])
                .expect("destination and operand registers are distinct");
            (d, Arg::Slice(s), other(b))
        }
        (None, Some(rb)) => {
            let [d, s] = registers
                .get_disjoint_mut([block(dst), block(rb)])
                .expect("destination and operand registers are distinct");
            (d, other(a), Arg::Slice(s))
        }
        (Some(ra), Some(rb)) if ra == rb => {
            let [d, s] = registers
                .get_disjoint_mut([block(dst), block(ra)])
                .expect("destination and operand registers are distinct");
            let s: &'a [f64] = s;
            (d, Arg::Slice(s), Arg::Slice(s))
        }
        (Some(ra), Some(rb)) => {
            let [d, sa, sb] = registers
                .get_disjoint_mut([block(dst), block(ra), block(rb)])
                .expect("destination and operand registers are distinct");
            (d, Arg::Slice(sa), Arg::Slice(sb))
        }
    }
}

#[inline(always)]
fn map1(dst: &mut [f64], a: Arg, f: impl Fn(f64) -> f64) {
    match a {
        Arg::Slice(a) => dst.iter_mut().zip(a).for_each(|(d, &x)| *d = f(x)),
        Arg::Scalar(x) => dst.fill(f(x)),
    }
}

#[inline(always)]
fn map2(dst: &mut [f64], a: Arg, b: Arg, f: impl Fn(f64, f64) -> f64) {
    match (a, b) {
        (Arg::Slice(a), Arg::Slice(b)) => dst
            .iter_mut()
            .zip(a.iter().zip(b))
            .for_each(|(d, (&x, &y))| *d = f(x, y)),
        (Arg::Slice(a), Arg::Scalar(y)) => dst.iter_mut().zip(a).for_each(|(d, &x)| *d = f(x, y)),
        (Arg::Scalar(x), Arg::Slice(b)) => dst.iter_mut().zip(b).for_each(|(d, &y)| *d = f(x, y)),
        (Arg::Scalar(x), Arg::Scalar(y)) => dst.fill(f(x, y)),
    }
}

crate::linalg::simd::per_node_kernel! {
    wide:
    /// The instructions of a program over one block of `lanes` points: [`apply`]'s passes,
    /// compiled for AVX2 and AVX-512 too (see [`crate::linalg::simd`]), the CPU asked once per
    /// block rather than once per instruction — which matters for the few points of a UKF's
    /// sigma set.
    fn run_code(code: &[Instruction], inputs: &[&[f64]], lanes: usize, registers: &mut [f64]) {
        for ins in code {
            let (dst, a, b) = operands(registers, lanes, ins.dst, &ins.operation, inputs);
            apply(&ins.operation, dst, a, b);
        }
    }
}

/// One pass of `operation` over the block; the arithmetic arms and `exp`, `ln`, `abs`,
/// `atan` and `sqrt` are monomorphic loops that vectorise; other functions are called per
/// value.
#[inline(always)]
fn apply(operation: &Operation, dst: &mut [f64], a: Arg<'_>, b: Arg<'_>) {
    match *operation {
        Operation::Neg(_) => map1(dst, a, |x| -x),
        Operation::Unary(f, _) => map1(dst, a, f),
        Operation::Exp(_) => map1(dst, a, crate::linalg::elementary::exp),
        Operation::Ln(_) => map1(dst, a, crate::linalg::elementary::ln),
        Operation::Abs(_) => map1(dst, a, libm::fabs),
        Operation::Atan(_) => map1(dst, a, crate::linalg::elementary::atan),
        Operation::Sqrt(_) => map1(dst, a, crate::linalg::elementary::sqrt),
        Operation::Add(..) => map2(dst, a, b, |x, y| x + y),
        Operation::Sub(..) => map2(dst, a, b, |x, y| x - y),
        Operation::Mul(..) => map2(dst, a, b, |x, y| x * y),
        Operation::Div(..) => map2(dst, a, b, |x, y| x / y),
        Operation::PowI(_, k) => match k {
            2 => map1(dst, a, |x| x * x),
            3 => map1(dst, a, |x| x * x * x),
            _ => map1(dst, a, |x| pow_int(x, k)),
        },
        Operation::Binary(f, ..) => map2(dst, a, b, f),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testing::test;

    /// (x + 2)·(x + 2) − 3/x: values shared by two operands, constants on either side.
    fn sample() -> Program {
        let ssa = [
            Operation::Add(Operand::Var(0), Operand::Const(2.0)),
            Operation::Mul(Operand::Reg(0), Operand::Reg(0)),
            Operation::Div(Operand::Const(3.0), Operand::Var(0)),
            Operation::Sub(Operand::Reg(1), Operand::Reg(2)),
        ];
        Program::from_ssa(&ssa, &[Operand::Reg(3)])
    }

    #[test]
    fn registers_are_reused_and_batches_match_points() {
        let p = sample();
        assert!(p.registers() <= 3, "{} registers", p.registers());
        let xs: Vec<f64> = (0..600).map(|i| 0.37 + i as f64 * 0.011).collect();
        let mut out = alloc::vec![0.0; xs.len()];
        let mut regs = alloc::vec![0.0; p.registers() * xs.len()];
        p.run(&[&xs], xs.len(), &mut regs, &mut out);
        for (x, v) in xs.iter().zip(&out) {
            let expected = (x + 2.0) * (x + 2.0) - 3.0 / x;
            assert_eq!(v.to_bits(), expected.to_bits());
            assert_eq!(p.eval(&[*x]).to_bits(), expected.to_bits());
        }
    }

    #[test]
    fn dead_values_are_not_computed() {
        let ssa = [
            Operation::Unary(libm::exp, Operand::Var(0)),
            Operation::Neg(Operand::Var(0)),
        ];
        let p = Program::from_ssa(&ssa, &[Operand::Reg(1)]);
        assert_eq!(p.len(), 1);
        assert_eq!(p.eval(&[2.5]), -2.5);
    }

    #[test]
    fn integer_powers_by_multiplication() {
        for k in 0..=MAX_POWI {
            for &x in &[0.3, -1.7, 2.0, 1e-3, 123.456] {
                let exact = libm::pow(x, k as f64);
                let ours = pow_int(x, k);
                let ulp = (exact.to_bits() as i64 - ours.to_bits() as i64).abs();
                assert!(ulp <= 2, "x = {x}, k = {k}: {ulp} ulp");
            }
        }
    }
}
