"""The ULX3S board (issue "On a board"): the pipeline behind a UART host link, a depth-tested
framebuffer in block RAM, 640 x 480 scan-out and DVI, its whole-frame simulation and its
bitstream.

    uart.py         the FT231X's UART, bit level (receiver and transmitter)
    link.py         frames of host-port rows: sync, header, CRC-16, never half-applied
    protocol.py     the host side: a scene as frames (``python -m board send``, the simulation)
    framebuffer.py  the depth test and the colour and depth planes (block RAM)
    video.py        640 x 480 at 60 Hz timing, the integer scaler, three TMDS lanes
    tmds.py         the DVI 1.0 TMDS encoder, and its Python model and decoder
    top.py          the clocked core (sim and board) and the board top (PLL, serialiser)
    sim.py          the core on Verilator: link bytes in, one video frame's symbols out
    build.py        the bitstream through Amaranth's build system and the yowasp tools
"""
