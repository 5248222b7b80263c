// The batch test bench: a unit's Verilated model driven from C++, no Python in the clock loop.
//
//   harness IN.bin OUT.bin P_VALID P_READY SEED [TRACE FIRST LAST]
//
// TRACE: a VCD of the cycles FIRST..LAST. IN.bin: u64 rows, N_UNI int64 uniforms, then
// rows x N_IN row_t field values (raw). The source
// offers rows with random valid gaps (P_VALID) and holds each until it is accepted; the sink
// is ready with probability P_READY each cycle: the same rules as sim/stream.py's Traffic,
// from one generator (splitmix64). A stalled output must hold its payload: the harness checks
// that and fails naming the cycle. OUT.bin: u64 rows, i64 cycles, latency (-1: none; from the
// first row that is not a host write), culled, memory words read, clocks loading (host writes
// at the head), then rows x N_OUT row_t (int32 or int64, chosen per unit by sim/batch). Progress goes to
// stderr as "progress SENT OUTPUTS" lines.
// ports.h (generated per unit by sim/batch.py) defines N_IN, N_OUT, MANY, row_t, set_inputs and
// get_outputs; MEM, the number of texture memory ports, and their glue (mem_* below).
//
// After the uniforms, IN.bin holds the texture memory: i64 words, i64 line (responses per
// request), i64 latency (clocks from a request's acceptance to its first response), f64
// P_MEM (the chance that the memory takes a request, and that it offers a response, each
// clock: its random stalls), then the words (i64). The memory answers each request with the
// line's words in order, one a clock at most, the requests in order; a stalled request must
// hold, like any output.
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <deque>
#include <vector>

#include "Vtop.h"
#include "verilated.h"
#if VM_TRACE
#include "verilated_vcd_c.h"
#endif

static inline int64_t sext(uint64_t v, int w) {
    return w >= 64 ? (int64_t)v : (int64_t)(v << (64 - w)) >> (64 - w);
}

#include "ports.h"

struct Rng {  // splitmix64: a double in [0, 1)
    uint64_t s;
    double next() {
        uint64_t z = (s += 0x9e3779b97f4a7c15ULL);
        z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
        z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
        return (double)((z ^ (z >> 31)) >> 11) * 0x1.0p-53;
    }
};

static void fail(const char* what, uint64_t cycle) {
    fprintf(stderr, "error: %s at cycle %llu\n", what, (unsigned long long)cycle);
    exit(3);
}

int main(int argc, char** argv) {
    if (argc != 6 && argc != 9) {
        fprintf(stderr, "usage: %s IN OUT P_VALID P_READY SEED [TRACE FIRST LAST]\n", argv[0]);
        return 2;
    }
    FILE* f = fopen(argv[1], "rb");
    uint64_t n = 0;
    if (!f || fread(&n, 8, 1, f) != 1) fail("cannot read the input file", 0);
    std::vector<int64_t> uni(N_UNI + 1);
    if (N_UNI && fread(uni.data(), 8, N_UNI, f) != N_UNI) fail("short input file", 0);
    int64_t mem_head[3] = {0, 1, 0};
    double p_mem = 1.0;
    if (fread(mem_head, 8, 3, f) != 3 || fread(&p_mem, 8, 1, f) != 1)
        fail("short input file", 0);
    std::vector<int64_t> memory(mem_head[0] + 1);
    if (mem_head[0] && fread(memory.data(), 8, mem_head[0], f) != (size_t)mem_head[0])
        fail("short input file", 0);
    const uint64_t mem_words = mem_head[0], mem_line = mem_head[1], mem_latency = mem_head[2];
    std::vector<row_t> in(n * N_IN + 1);
    if (n && fread(in.data(), sizeof(row_t), n * N_IN, f) != n * N_IN)
        fail("short input file", 0);
    fclose(f);
    const double p_valid = atof(argv[3]), p_ready = atof(argv[4]);
    Rng rng{strtoull(argv[5], nullptr, 10)};

    VerilatedContext ctx;
    Vtop* top = new Vtop{&ctx};
    uint64_t trace_first = 0, trace_last = 0;
#if VM_TRACE
    VerilatedVcdC* tfp = nullptr;
    if (argc == 9) {
        ctx.traceEverOn(true);
        tfp = new VerilatedVcdC;
        top->trace(tfp, 99);
        tfp->open(argv[6]);
        trace_first = strtoull(argv[7], nullptr, 10);
        trace_last = strtoull(argv[8], nullptr, 10);
    }
#endif
    auto tick = [&](uint64_t cycle, int clk) {
        top->clk = clk;
        top->eval();
#if VM_TRACE
        if (tfp && cycle >= trace_first && cycle <= trace_last) tfp->dump(2 * cycle + clk);
#endif
    };
    set_uniforms(top, uni.data());
    top->rst = 1;
    top->i_valid = 0;
    top->o_ready = 0;
    for (int k = 0; k < 2; k++) { tick(0, 0); tick(0, 1); }
    top->rst = 0;

    // the memory, per port: requests taken, each with the cycle its first word is due
    struct Burst { uint64_t due, addr, next; };
    struct Port {
        std::deque<Burst> bursts;
        bool resp_valid = false, req_was_held = false, take = false;
        uint64_t resp_data = 0, held_addr = 0;
        Rng rng{0};
    };
    std::vector<Port> ports(MEM + 1);
    for (int p = 0; p <= MEM; p++) ports[p].rng.s = strtoull(argv[5], nullptr, 10) ^ (0x5eedULL + p);
    uint64_t mem_reads = 0;
    std::vector<row_t> out;
    if (!MANY) out.reserve(n * N_OUT);
    std::vector<row_t> cur(N_OUT + 1), held(N_OUT + 1);
    bool valid = false, was_held = false, busy = true;
    uint64_t sent = 0, cycles = 0, quiet = 0, outs = 0;
    int64_t first_in = -1, first_out = -1;
    const double rate = p_valid * p_ready > 1e-3 ? p_valid * p_ready : 1e-3;
    const uint64_t max_cycles = 64 + (uint64_t)(4.0 * n / rate);
    for (;;) {
        if (MANY ? (sent >= n && !busy) : outs >= n) break;
        if (!valid && sent < n) valid = p_valid >= 1.0 || rng.next() < p_valid;
        const bool ready = p_ready >= 1.0 || rng.next() < p_ready;
        top->i_valid = valid;
        if (valid) set_inputs(top, &in[sent * N_IN]);
        top->o_ready = ready;
        for (int p = 0; p < MEM; p++) {
            Port& q = ports[p];
            q.take = p_mem >= 1.0 || q.rng.next() < p_mem;
            mem_set(top, p, q.take, q.resp_valid, q.resp_data);
        }
        tick(cycles, 0);
        const bool i_ready = top->i_ready, o_valid = top->o_valid;
        if (o_valid) get_outputs(top, cur.data());
        if (was_held && (!o_valid || memcmp(cur.data(), held.data(), sizeof(row_t) * N_OUT)))
            fail("a stalled output changed or was withdrawn before it was taken", cycles);
        was_held = o_valid && !ready;
        if (was_held) held = cur;
        bool mem_moved = false;
        for (int p = 0; p < MEM; p++) {
            Port& q = ports[p];
            uint64_t addr = 0;
            const bool req = mem_req(top, p, &addr);
            if (q.req_was_held && (!req || addr != q.held_addr))
                fail("a stalled memory request changed or was withdrawn before it was taken",
                     cycles);
            q.req_was_held = req && !q.take;
            q.held_addr = addr;
            if (req && q.take) {
                if (addr % mem_line || addr + mem_line > mem_words)
                    fail("a memory request outside the texture memory, or not aligned to a "
                         "line", cycles);
                q.bursts.push_back({cycles + mem_latency, addr, 0});
                mem_moved = true;
            }
            if (q.resp_valid && mem_resp_ready(top, p)) q.resp_valid = false, mem_moved = true;
        }
        const bool taken = valid && i_ready;
        if (taken) {
            // the latency starts at the first triangle, not at a host write (CMD: its field)
            if (first_in < 0 && (CMD < 0 || in[sent * N_IN + (CMD < 0 ? 0 : CMD)] == 0))
                first_in = cycles;
            sent++;
            valid = false;
        }
        if (o_valid && ready) {
            if (first_out < 0) first_out = cycles;
            out.insert(out.end(), cur.begin(), cur.begin() + N_OUT);
            outs++;
        }
#if MANY
        busy = top->busy || o_valid || taken;  // busy is sampled before the edge
#endif
        tick(cycles, 1);
        cycles++;
        // each port's next response: its oldest burst's next word, once due (random gaps)
        for (int p = 0; p < MEM; p++) {
            Port& q = ports[p];
            if (!q.resp_valid && !q.bursts.empty() && q.bursts.front().due <= cycles &&
                (p_mem >= 1.0 || q.rng.next() < p_mem)) {
                Burst& b = q.bursts.front();
                q.resp_data = (uint64_t)memory[b.addr + b.next];
                q.resp_valid = true;
                mem_reads++;
                if (++b.next == mem_line) q.bursts.pop_front();
            }
            busy = busy || q.resp_valid || !q.bursts.empty();
        }
        quiet = (taken || (o_valid && ready) || mem_moved) ? 0 : quiet + 1;
        if (MANY ? quiet > 100000 : cycles > max_cycles) {
#if HELD
            char what[160];
            snprintf(what, sizeof what, "no progress (nothing crossed any interface; held=%llx)",
                     (unsigned long long)top->held);
            fail(what, cycles);
#else
            fail("no progress (nothing crossed either interface)", cycles);
#endif
        }
        if (!(cycles & ((1u << 20) - 1))) {
            fprintf(stderr, "progress %llu %llu\n", (unsigned long long)sent,
                    (unsigned long long)outs);
        }
    }
#if VM_TRACE
    if (tfp) tfp->close();
#endif
    int64_t culled = 0, loading = 0;
#if MANY
    culled = top->culled;
#endif
#if CMD >= 0
    loading = top->loading;
#endif
    top->final();
    delete top;
    FILE* g = fopen(argv[2], "wb");
    if (!g) fail("cannot write the output file", cycles);
    const int64_t head[6] = {(int64_t)outs, (int64_t)cycles,
                             first_out < 0 ? -1 : first_out - first_in, culled,
                             (int64_t)mem_reads, loading};
    fwrite(head, 8, 6, g);
    fwrite(out.data(), sizeof(row_t), out.size(), g);
    fclose(g);
    return 0;
}
