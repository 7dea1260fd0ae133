//! The `@( )` arithmetic of MFIX decks: any text, and the same text amplified into deep
//! nestings (parentheses, signs, `**` chains). The evaluator must return a number or a message
//! and never overflow the stack: nesting is capped at `MAX_EXPR_DEPTH` levels. The deck
//! lexer sees the same expressions inside an assignment.
#![no_main]

use grainflow_case::mfix::lexer::{MAX_EXPR_DEPTH, eval_expr, lex_deck};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Some((&shape, rest)) = data.split_first() else { return };
    let text = String::from_utf8_lossy(rest);
    // The text as it is, and as the core of a nesting up to 16 times the cap deep: the first
    // byte chooses the kind of nesting and its depth.
    let depth = (shape as usize % 16 + 1) * MAX_EXPR_DEPTH;
    let nested = match shape % 4 {
        0 => format!("{}{text}{}", "(".repeat(depth), ")".repeat(depth)),
        1 => format!("{}{text}", "-".repeat(depth)),
        2 => format!("{}{text}", "2**".repeat(depth)),
        _ => format!("{}{text}{}", "(-".repeat(depth), ")".repeat(depth)),
    };
    for expr in [text.as_ref(), nested.as_str()] {
        if let Ok(v) = eval_expr(expr) {
            assert!(v.is_finite(), "@({expr}) gave {v}");
        }
        let _ = lex_deck(&format!("KN = @({expr})\n"), "mfix.dat");
    }
});
