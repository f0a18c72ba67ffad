"""What a comparison runs: cases, plans, kinds, mutants, margins and statistics."""
