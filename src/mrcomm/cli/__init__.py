"""The ``mrcomm`` command line."""
