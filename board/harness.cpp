// The board core on Verilator (board/sim.py): link bytes in, as the host sends them, then one
// whole video frame's TMDS symbols out. Two clocks: the core (sync) and the pixel clock, in
// the PLL's ratio (a pixel edge whenever the accumulated ratio passes a whole one).
//
//   harness IN OUT PACE RATIO_NUM RATIO_DEN
// IN: u32 frame count, then per frame u32 length and its bytes; bit 31 of the length set:
// bytes that expect no reply (noise). PACE: core clocks a byte (the UART's 10 bits). After
// each frame it waits for the link's reply (the frames count), as the host does. Then it waits for the pipeline to drain and the next frame start, and writes OUT:
// u32 clocks to render, u32 symbol count, the symbols (u16 x 3 per pixel clock), u32 reply
// bytes and the replies. Progress on stderr: "frame K N".
#include <cstdio>
#include <cstdint>
#include <cstdlib>
#include <vector>
#include "Vtop.h"
#include "verilated.h"

static Vtop *top;
static uint64_t acc = 0, num = 1, den = 4, core_clocks = 0;
static std::vector<uint8_t> replies;

static void pixel_edge() {
    top->pixel_clk = 1; top->eval();
    top->pixel_clk = 0; top->eval();
}

// one core clock; true if a pixel edge followed it
static bool core_clock() {
    top->clk = 1; top->eval();
    if (top->tx_valid) replies.push_back(top->tx_data);
    top->clk = 0; top->eval();
    core_clocks++;
    acc += num;
    if (acc < den) return false;
    acc -= den;
    pixel_edge();
    return true;
}

static void fail(const char *what) {
    fprintf(stderr, "harness: %s (after %llu core clocks)\n", what, (unsigned long long)core_clocks);
    exit(2);
}

int main(int argc, char **argv) {
    if (argc != 6) fail("usage: harness IN OUT PACE RATIO_NUM RATIO_DEN");
    uint64_t pace = atoll(argv[3]);
    num = atoll(argv[4]); den = atoll(argv[5]);
    FILE *in = fopen(argv[1], "rb");
    if (!in) fail("cannot open the input");
    uint32_t nframes;
    if (fread(&nframes, 4, 1, in) != 1) fail("short input");
    Verilated::commandArgs(argc, argv);
    top = new Vtop;
    top->tx_ready = 1;
    top->rst = 1; top->pixel_rst = 1;
    for (int k = 0; k < 8; k++) { core_clock(); pixel_edge(); }
    top->rst = 0; top->pixel_rst = 0;
    for (uint32_t f = 0; f < nframes; f++) {
        uint32_t len;
        if (fread(&len, 4, 1, in) != 1) fail("short input");
        bool answered = !(len >> 31);
        len &= 0x7fffffffu;
        std::vector<uint8_t> bytes(len);
        if (fread(bytes.data(), 1, len, in) != len) fail("short input");
        uint32_t before = top->frames;
        for (uint32_t k = 0; k < len; k++) {
            top->rx_valid = 1; top->rx_data = bytes[k];
            core_clock();
            top->rx_valid = 0;
            for (uint64_t p = 1; p < pace; p++) core_clock();
        }
        uint64_t waited = 0;
        while (answered && top->frames == before) {           // the host waits for the reply
            core_clock();
            if (++waited > 200000000ull) fail("no reply to a frame");
        }
        fprintf(stderr, "frame %u %u\n", f + 1, nframes);
    }
    while (top->busy) core_clock();
    uint64_t render = core_clocks;
    // the next frame start, then one whole frame of symbols
    uint64_t guard = 0;
    while (!top->first) {
        while (!core_clock()) {}
        if (++guard > 1000000ull) fail("no frame start");
    }
    const uint32_t total = 800 * 525;
    std::vector<uint16_t> sym;
    sym.reserve(3 * total);
    while (sym.size() < 3ull * total) {
        uint16_t s0 = top->symbols & 0x3FF, s1 = (top->symbols >> 10) & 0x3FF,
                 s2 = (top->symbols >> 20) & 0x3FF;
        if (sym.empty() && !top->first) fail("lost the frame start");
        sym.push_back(s0); sym.push_back(s1); sym.push_back(s2);
        while (!core_clock()) {}                 // on to the next pixel clock
    }
    FILE *out = fopen(argv[2], "wb");
    if (!out) fail("cannot open the output");
    uint32_t r32 = (uint32_t)render, n = total, nr = replies.size();
    fwrite(&r32, 4, 1, out); fwrite(&n, 4, 1, out);
    fwrite(sym.data(), 2, sym.size(), out);
    fwrite(&nr, 4, 1, out); fwrite(replies.data(), 1, nr, out);
    fclose(out);
    delete top;
    return 0;
}
