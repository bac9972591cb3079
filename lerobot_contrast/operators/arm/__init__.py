"""The arm as its own operator (`--operator=arm`): its flags (args), how it is built (setup), the operator (operator),
what staging has spent (memory), its joints' measurement (joints) and its camera's verdict (verdict). Light: each
module is imported where it is needed (args before anything heavy loads)."""
