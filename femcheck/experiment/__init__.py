"""Virtual experiments: synthetic measured data with hidden model errors (issue 7 item 8)."""
