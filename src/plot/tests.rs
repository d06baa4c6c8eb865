use super::axes::{Span, decade_range, decade_ticks, format_sig, log_label};
use super::figure::ImageFormat;
use std::path::Path;

#[test]
fn formats_from_extension() {
    assert_eq!(
        ImageFormat::from_path(Path::new("a/b.PNG")).unwrap(),
        ImageFormat::Png
    );
    assert_eq!(
        ImageFormat::from_path(Path::new("b.svg")).unwrap(),
        ImageFormat::Svg
    );
    for bad in ["b.jpg", "b", "b.png.txt"] {
        let e = ImageFormat::from_path(Path::new(bad)).unwrap_err();
        assert_eq!(e.exit_code(), 2, "{bad}");
    }
}

#[test]
fn log_labels() {
    assert_eq!(log_label(1e-5), "10⁻⁵");
    assert_eq!(log_label(1.0), "10⁰");
    assert_eq!(log_label(1e3 * (1.0 - 1e-12)), "10³");
    assert_eq!(log_label(2e-5), "2·10⁻⁵");
    assert_eq!(format_sig(1e-9, 2), "1e-9");
    assert_eq!(format_sig(3.52e-12, 3), "3.52e-12");
    assert_eq!(format_sig(0.126, 2), "0.13");
    assert_eq!(format_sig(1234.6, 4), "1235");
}

#[test]
fn spans_are_drawable() {
    let mut s = Span::EMPTY;
    assert_eq!(s.padded(0.1, (0.0, 1.0)), (0.0, 1.0));
    s.include(f64::NAN);
    s.include(3.0);
    let (lo, hi) = s.padded(0.0, (0.0, 1.0));
    assert!(lo < 3.0 && hi > 3.0);
    let (a, b) = decade_range(Span { lo: 3e-7, hi: 4e-7 });
    assert!(a <= -7.0 && b >= -6.0 && b - a >= 2.0);
    assert_eq!(
        decade_range(Span {
            lo: 1e-310,
            hi: 1e300
        }),
        (-400.0, 300.0)
    );
    // Thirty decades: labels every five, and both ends on a label.
    let r = decade_range(Span {
        lo: 3e-28,
        hi: 0.02,
    });
    assert_eq!(r, (-30.0, 0.0));
    assert_eq!(decade_ticks(r), 9);
}
