//! `--style` and `--brush`, shared by `strata render` and `strata view` so that both
//! accept the same names and refuse the same mistakes with the same one-line errors.

use crate::gpu::{Brush, NprKind, RenderStyle};

/// How samples are drawn: splats, or stipple dots or brush strokes on paper.
#[derive(Debug, Clone, clap::Args)]
pub struct StyleArgs {
    /// How samples are drawn: `splats` (field-aligned ellipses or glyphs), `stipple`
    /// (ink dots sized by tone) or `strokes` (brush strokes along the field, see
    /// `--brush`); stipple and strokes are drawn on paper (docs/styles.md).
    #[arg(long, default_value = "splats")]
    pub style: String,
    /// With `--style strokes`: the brush, `acrylic`, `crayon`, `watercolor`, `pencil`
    /// or `ink` (default acrylic).
    #[arg(long)]
    pub brush: Option<String>,
}

impl StyleArgs {
    /// The stroke or stipple look `--style` and `--brush` ask for (`None` for splats),
    /// or a one-line error naming the valid choices.
    pub fn npr_kind(&self) -> anyhow::Result<Option<NprKind>> {
        let Some(style) = RenderStyle::from_name(&self.style) else {
            anyhow::bail!(
                "--style must be one of {}, not '{}'",
                RenderStyle::NAMES.join(", "),
                self.style
            );
        };
        let brush = match self.brush.as_deref() {
            None => None,
            Some(_) if style != RenderStyle::Strokes => {
                anyhow::bail!(
                    "--brush needs --style strokes (not --style {})",
                    style.name()
                )
            }
            Some(name) => Some(Brush::from_name(name).ok_or_else(|| {
                anyhow::anyhow!(
                    "--brush must be one of {}, not '{name}'",
                    Brush::NAMES.join(", ")
                )
            })?),
        };
        Ok(match style {
            RenderStyle::Splats => None,
            RenderStyle::Stipple => Some(NprKind::Stipple),
            RenderStyle::Strokes => Some(NprKind::Strokes(brush.unwrap_or_default())),
        })
    }

    /// [`npr_kind`](Self::npr_kind), refusing `--lod` (`lod`) with stipple and strokes,
    /// which do not support it yet.
    pub fn npr_kind_for(&self, lod: bool) -> anyhow::Result<Option<NprKind>> {
        let kind = self.npr_kind()?;
        if kind.is_some() && lod {
            anyhow::bail!("--style {} does not support --lod yet", self.style);
        }
        Ok(kind)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn args(style: &str, brush: Option<&str>) -> StyleArgs {
        StyleArgs {
            style: style.into(),
            brush: brush.map(Into::into),
        }
    }

    #[test]
    fn styles_and_brushes_parse_into_kinds() {
        assert_eq!(args("splats", None).npr_kind().expect("splats"), None);
        assert_eq!(
            args("stipple", None).npr_kind().expect("stipple"),
            Some(NprKind::Stipple)
        );
        assert_eq!(
            args("strokes", None).npr_kind().expect("strokes"),
            Some(NprKind::Strokes(Brush::Acrylic))
        );
        assert_eq!(
            args("strokes", Some("pencil")).npr_kind().expect("pencil"),
            Some(NprKind::Strokes(Brush::Pencil))
        );
    }

    #[test]
    fn lod_is_refused_only_with_stipple_and_strokes() {
        assert!(args("splats", None).npr_kind_for(true).is_ok());
        let e = args("stipple", None)
            .npr_kind_for(true)
            .expect_err("stipple with --lod");
        assert_eq!(e.to_string(), "--style stipple does not support --lod yet");
        assert!(args("strokes", None).npr_kind_for(false).is_ok());
    }
}
