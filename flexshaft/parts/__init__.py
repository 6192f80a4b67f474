"""Part models: 1D and solid parts (K, M, masters, recovery), with one constraint step."""
