"""The ``radio`` network model: path loss with walls, correlated shadowing, fading,
packet error from SNR and message size, and a transmit queue with finite capacity."""
