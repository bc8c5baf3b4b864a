"""ballaststudy: ballast gradation and stone-shape study (Wang 2018, Stuttgart) as one open chain."""

__version__ = "0.1.0"
