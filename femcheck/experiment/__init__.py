"""Virtual experiments: synthetic measured data with hidden model errors."""
