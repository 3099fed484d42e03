"""Run time: the bus nodes talk over and the schedulers that tick them."""

# Where a robot listens for its station by default (zenoh's own port is 7447): here, not in
# the zenoh bus, so that the commands' options are listed without loading zenoh.
DEFAULT_ENDPOINT = "tcp/127.0.0.1:7447"
