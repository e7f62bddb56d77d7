use super::lexer::{Lexer, TokenKind};
use super::*;
use crate::math::Vec3;
use std::path::PathBuf;
use std::sync::Arc;

// ---- tokenizer --------------------------------------------------------------

fn tokens(text: &str) -> Vec<(TokenKind, u32, u32)> {
    let mut lx = Lexer::new(Arc::new(PathBuf::from("t.pbrt")), text.as_bytes().to_vec()).unwrap();
    let mut out = vec![];
    while let Some(t) = lx.next_token().unwrap() {
        out.push((t.kind, t.loc.line, t.loc.col));
    }
    out
}

fn num(v: f64) -> TokenKind {
    TokenKind::Num { value: v, int: None }
}

fn int(i: i64) -> TokenKind {
    TokenKind::Num {
        value: i as f64,
        int: Some(i),
    }
}

fn word(w: &str) -> TokenKind {
    TokenKind::Word(w.into())
}

#[test]
fn tokens_carry_line_and_column() {
    let text = "# a comment\nShape \"sphere\" \"float radius\" [ 2.5 ]# tail\n\t  Translate -1 +2 .5e1\n\"é\" x[1]\r\n";
    assert_eq!(
        tokens(text),
        vec![
            (word("Shape"), 2, 1),
            (TokenKind::Str("sphere".into()), 2, 7),
            (TokenKind::Str("float radius".into()), 2, 16),
            (TokenKind::Open, 2, 31),
            (num(2.5), 2, 33),
            (TokenKind::Close, 2, 37),
            (word("Translate"), 3, 4),
            (int(-1), 3, 14),
            (int(2), 3, 17),
            (num(5.0), 3, 20),
            (TokenKind::Str("é".into()), 4, 1),
            // Columns count characters: "é" is one.
            (word("x"), 4, 5),
            (TokenKind::Open, 4, 6),
            (int(1), 4, 7),
            (TokenKind::Close, 4, 8),
        ]
    );
}

#[test]
fn tokens_strings_escapes_and_malformed_numbers() {
    assert_eq!(
        tokens(r#""a\"b\\c\n" 1.2.3 inf 1e999 -"#),
        vec![
            (TokenKind::Str("a\"b\\c\n".into()), 1, 1),
            (word("1.2.3"), 1, 13),
            (word("inf"), 1, 19),
            (word("1e999"), 1, 23),
            (word("-"), 1, 29),
        ]
    );
    // A word runs up to a quote or bracket.
    assert_eq!(
        tokens("ab\"c\"]"),
        vec![
            (word("ab"), 1, 1),
            (TokenKind::Str("c".into()), 1, 3),
            (TokenKind::Close, 1, 6)
        ]
    );
}

fn lex_error(text: &[u8]) -> String {
    let mut lx = match Lexer::new(Arc::new(PathBuf::from("t.pbrt")), text.to_vec()) {
        Ok(lx) => lx,
        Err(e) => return e.to_string(),
    };
    loop {
        match lx.next_token() {
            Ok(Some(_)) => {}
            Ok(None) => panic!("no error"),
            Err(e) => return e.to_string(),
        }
    }
}

#[test]
fn tokenizer_errors_name_the_place() {
    assert_eq!(
        lex_error(b"Shape \"sphere\n\"x\""),
        "t.pbrt:1:7: unterminated string: a string must end on the line it starts"
    );
    assert_eq!(
        lex_error(b"\n  \"abc"),
        "t.pbrt:2:3: unterminated string: the file ends inside it"
    );
    assert_eq!(lex_error(b"\"a\\qb\""), "t.pbrt:1:4: unknown escape '\\q' in a string");
    assert_eq!(lex_error(b"ok\n ab\xff"), "t.pbrt:2:4: the file is not UTF-8 text");
    assert!(lex_error(b"\xff\xfeS\0").contains("UTF-16"));
}

// ---- spectra ----------------------------------------------------------------

fn chromaticity(xyz: Vec3) -> (f32, f32) {
    let sum = xyz.x + xyz.y + xyz.z;
    (xyz.x / sum, xyz.y / sum)
}

#[test]
fn blackbody_colours_are_on_the_planckian_locus() {
    // CIE 1931 chromaticities of the Planckian radiator: 6504 K (D65's CCT)
    // and 2856 K (illuminant A).
    let (x, y) = chromaticity(spectrum::blackbody_xyz(6504.0));
    assert!((x - 0.3135).abs() < 0.003 && (y - 0.3236).abs() < 0.003, "{x} {y}");
    let (x, y) = chromaticity(spectrum::blackbody_xyz(2856.0));
    assert!((x - 0.4476).abs() < 0.003 && (y - 0.4074).abs() < 0.003, "{x} {y}");
    // Near-white at 6504 K, red above blue at 3000 K.
    let c = spectrum::blackbody_rgb(6504.0);
    assert!((c.x / c.z - 1.0).abs() < 0.05 && (c.y / c.z - 1.0).abs() < 0.05, "{c}");
    let c = spectrum::blackbody_rgb(3000.0);
    assert!(c.x > c.y && c.y > c.z, "{c}");
    // pbrt's lights see unit luminance.
    let l = SpectrumValue::Blackbody(3000.0).light_rgb().unwrap();
    assert!((spectrum::luminance(l) - 1.0).abs() < 0.01, "{l}");
    assert_eq!(SpectrumValue::Rgb(Vec3::ONE).light_rgb(), Some(Vec3::ONE));
    assert_eq!(SpectrumValue::Named("stdillum-D65".into()).to_rgb(), None);
    // A constant spectrum of 1 has Y = 1 (equal-energy white).
    let flat = SampledSpectrum {
        lambda: vec![300.0, 900.0],
        value: vec![1.0, 1.0],
    };
    assert!((spectrum::spectrum_to_xyz(|l| flat.eval(l)).y - 1.0).abs() < 1e-4);
    // The peak-normalised spectrum has a maximum of 1.
    let peak = (360..=830)
        .map(|l| spectrum::blackbody_normalized(l as f64, 6000.0))
        .fold(0.0, f64::max);
    assert!((peak - 1.0).abs() < 1e-3, "{peak}");
    assert_eq!(spectrum::blackbody_normalized(500.0, 0.0), 0.0);
}
