"""The 4T pinned-photodiode pixel with true CDS (family ``pixel4t``): docs/pixel4t.md."""
