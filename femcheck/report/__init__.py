"""Report writers (tables, HTML, plots); one module per report."""
