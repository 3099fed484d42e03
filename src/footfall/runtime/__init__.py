"""Run time: the bus nodes talk over and the schedulers that tick them."""
