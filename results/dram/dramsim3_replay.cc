// dramsim3_replay.cc -- rtsim's open-loop trace driver for DRAMsim3, the
// independent DDR simulator results/dram compares the banked level with.
// Not part of rtsim's build: compile it against a DRAMsim3 build (README here).
// Usage: replay CONFIG.ini TRACE [--cycles-limit N] [--per-request FILE]
//                               [--out-dir DIR] [--quiet-stats]
// TRACE lines: 0xHEXADDR READ|WRITE DRAMCYCLE [ignored extra columns]
// Lines starting with '#' (after optional whitespace) and blank lines are skipped.
//
// Semantics (mirrors DRAMsim3's TraceBasedCPU::ClockTick):
//   for clk = 0,1,2,...:
//     mem.ClockTick();                         // callbacks for clk fire in here
//     if next request's arrival <= clk:
//        if mem.WillAcceptTransaction(): AddTransaction(); accept_cycle = clk
//        else: retry next cycle, later requests wait behind it (in order)
//   at most ONE request is offered per cycle (TraceBasedCPU does the same).
//   Stop when every request has had its read/write callback (or cycles-limit).
#include <algorithm>
#include <cinttypes>
#include <cstdio>
#include <cstdlib>
#include <deque>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <unordered_map>
#include <vector>
#include <sys/stat.h>

#include "memory_system.h"
#include "json.hpp"  // DRAMsim3's bundled nlohmann::json (ext/headers)

struct Req {
    uint64_t addr;
    bool is_write;
    uint64_t arrival;
    int64_t accept = -1;
    int64_t done = -1;
};

static void usage() {
    std::cerr << "usage: replay CONFIG.ini TRACE [--cycles-limit N] "
                 "[--per-request FILE] [--out-dir DIR]\n";
    std::exit(2);
}

static double pct(std::vector<uint64_t> v, double p) {
    if (v.empty()) return 0;
    std::sort(v.begin(), v.end());
    size_t rank = (size_t)std::ceil(p / 100.0 * v.size());
    if (rank < 1) rank = 1;
    return (double)v[rank - 1];
}
static double mean(const std::vector<uint64_t>& v) {
    if (v.empty()) return 0;
    long double s = 0;
    for (auto x : v) s += x;
    return (double)(s / v.size());
}

int main(int argc, char** argv) {
    if (argc < 3) usage();
    std::string cfg = argv[1], trace = argv[2], per_req, out_dir = ".";
    uint64_t limit = UINT64_MAX;
    for (int i = 3; i < argc; i++) {
        std::string a = argv[i];
        if (a == "--cycles-limit" && i + 1 < argc) limit = std::stoull(argv[++i]);
        else if (a == "--per-request" && i + 1 < argc) per_req = argv[++i];
        else if (a == "--out-dir" && i + 1 < argc) out_dir = argv[++i];
        else usage();
    }
    mkdir(out_dir.c_str(), 0755);

    // ---- read trace
    std::vector<Req> reqs;
    {
        std::ifstream in(trace);
        if (!in) { std::cerr << "cannot open trace " << trace << "\n"; return 1; }
        std::string line;
        size_t lineno = 0;
        while (std::getline(in, line)) {
            lineno++;
            size_t p = line.find_first_not_of(" \t\r");
            if (p == std::string::npos || line[p] == '#') continue;
            std::istringstream ss(line);
            std::string a, op, c;
            if (!(ss >> a >> op >> c)) {
                std::cerr << "bad trace line " << lineno << ": " << line << "\n";
                return 1;
            }
            Req r;
            r.addr = std::stoull(a, nullptr, 16);
            if (op == "READ" || op == "read") r.is_write = false;
            else if (op == "WRITE" || op == "write") r.is_write = true;
            else { std::cerr << "bad op line " << lineno << "\n"; return 1; }
            r.arrival = std::stoull(c);
            reqs.push_back(r);
        }
    }
    if (reqs.empty()) { std::cerr << "empty trace\n"; return 1; }
    for (size_t i = 1; i < reqs.size(); i++)
        if (reqs[i].arrival < reqs[i - 1].arrival) {
            std::cerr << "trace not sorted by cycle at request " << i << "\n";
            return 1;
        }

    // ---- callbacks: match by address, FIFO per address and per type
    std::unordered_map<uint64_t, std::deque<size_t>> pend_rd, pend_wr;
    uint64_t clk = 0;
    size_t completed = 0;
    auto on_done = [&](std::unordered_map<uint64_t, std::deque<size_t>>& m,
                       uint64_t addr, const char* kind) {
        auto it = m.find(addr);
        if (it == m.end() || it->second.empty()) {
            std::cerr << "unexpected " << kind << " callback for 0x" << std::hex
                      << addr << std::dec << " at " << clk << "\n";
            std::exit(1);
        }
        size_t idx = it->second.front();
        it->second.pop_front();
        reqs[idx].done = (int64_t)clk;
        completed++;
    };
    auto rcb = [&](uint64_t a) { on_done(pend_rd, a, "read"); };
    auto wcb = [&](uint64_t a) { on_done(pend_wr, a, "write"); };

    dramsim3::MemorySystem mem(cfg, out_dir, rcb, wcb);

    // ---- main loop
    size_t next = 0;
    for (clk = 0; completed < reqs.size() && clk < limit; clk++) {
        mem.ClockTick();
        if (next < reqs.size() && reqs[next].arrival <= clk) {
            Req& r = reqs[next];
            if (mem.WillAcceptTransaction(r.addr, r.is_write)) {
                // register before AddTransaction (callbacks only fire in ClockTick)
                (r.is_write ? pend_wr : pend_rd)[r.addr].push_back(next);
                mem.AddTransaction(r.addr, r.is_write);
                r.accept = (int64_t)clk;
                next++;
            }
        }
    }
    bool finished = completed == reqs.size();
    mem.PrintStats();

    // ---- metrics
    std::vector<uint64_t> rl, rl_acc, wl, wl_acc, qdelay;
    uint64_t nrd = 0, nwr = 0, last_done = 0;
    for (auto& r : reqs) {
        if (r.is_write) nwr++; else nrd++;
        if (r.done < 0) continue;
        last_done = std::max<uint64_t>(last_done, r.done);
        uint64_t l = r.done - r.arrival, la = r.done - r.accept;
        qdelay.push_back(r.accept - r.arrival);
        if (r.is_write) { wl.push_back(l); wl_acc.push_back(la); }
        else { rl.push_back(l); rl_acc.push_back(la); }
    }
    uint64_t first_arr = reqs.front().arrival;
    uint64_t cycles = finished ? last_done - first_arr : clk - first_arr;

    // DRAMsim3's own stats (json written by PrintStats)
    std::string prefix_json;
    {
        // output_prefix default is "dramsim3" unless the ini sets [other] output_prefix
        dramsim3::Config c(cfg, out_dir);
        prefix_json = c.json_stats_name;
    }
    nlohmann::json js;
    {
        std::ifstream jin(prefix_json);
        try { jin >> js; } catch (...) { std::cerr << "cannot parse " << prefix_json << "\n"; }
    }
    auto sumc = [&](const char* k) -> uint64_t {
        uint64_t s = 0;
        for (auto& ch : js) if (ch.contains(k)) s += ch[k].get<uint64_t>();
        return s;
    };
    // A double stat summed over channels; a per-rank one (an object by rank)
    // summed over its ranks too.
    auto sumd = [&](const char* k) -> double {
        double s = 0;
        for (auto& ch : js) {
            if (!ch.contains(k)) continue;
            if (ch[k].is_object())
                for (auto it = ch[k].begin(); it != ch[k].end(); ++it) s += it.value().get<double>();
            else s += ch[k].get<double>();
        }
        return s;
    };
    auto histo_mean = [&](const char* k) -> double {
        long double s = 0; uint64_t n = 0;
        for (auto& ch : js)
            if (ch.contains(k))
                for (auto it = ch[k].begin(); it != ch[k].end(); ++it) {
                    uint64_t cnt = it.value().get<uint64_t>();
                    s += (long double)std::stoll(it.key()) * cnt; n += cnt;
                }
        return n ? (double)(s / n) : 0.0;
    };

    printf("config=%s\ntrace=%s\n", cfg.c_str(), trace.c_str());
    printf("finished=%d\n", finished ? 1 : 0);
    printf("requests=%zu\nreads=%" PRIu64 "\nwrites=%" PRIu64 "\n", reqs.size(), nrd, nwr);
    printf("completed=%zu\n", completed);
    printf("sim_cycles=%" PRIu64 "\n", clk);
    printf("cycles=%" PRIu64 "\n", cycles);
    printf("read_latency_mean=%.3f\nread_latency_p50=%.0f\nread_latency_p95=%.0f\n"
           "read_latency_p99=%.0f\nread_latency_max=%.0f\n",
           mean(rl), pct(rl, 50), pct(rl, 95), pct(rl, 99), pct(rl, 100));
    printf("read_latency_from_accept_mean=%.3f\nread_latency_from_accept_p50=%.0f\n"
           "read_latency_from_accept_p95=%.0f\nread_latency_from_accept_p99=%.0f\n"
           "read_latency_from_accept_max=%.0f\n",
           mean(rl_acc), pct(rl_acc, 50), pct(rl_acc, 95), pct(rl_acc, 99), pct(rl_acc, 100));
    printf("write_latency_mean=%.3f\nwrite_latency_from_accept_mean=%.3f\n",
           mean(wl), mean(wl_acc));
    printf("accept_delay_mean=%.3f\naccept_delay_max=%.0f\n", mean(qdelay), pct(qdelay, 100));
    printf("bandwidth_bytes_per_cycle=%.4f\n",
           cycles ? 64.0 * completed / (double)cycles : 0.0);
    // DRAMsim3 internal counters
    const char* keys[] = {"num_cycles", "num_reads_done", "num_writes_done",
                          "num_read_cmds", "num_write_cmds", "num_read_row_hits",
                          "num_write_row_hits", "num_act_cmds", "num_pre_cmds",
                          "num_ondemand_pres", "num_ref_cmds", "num_refb_cmds",
                          "num_srefe_cmds", "num_srefx_cmds"};
    for (auto k : keys) printf("dramsim3.%s=%" PRIu64 "\n", k, sumc(k));
    uint64_t rw = sumc("num_read_cmds") + sumc("num_write_cmds");
    uint64_t hits = sumc("num_read_row_hits") + sumc("num_write_row_hits");
    printf("row_hit_rate=%.4f\n", rw ? (double)hits / rw : 0.0);
    printf("read_row_hit_rate=%.4f\n", sumc("num_read_cmds") ?
           (double)sumc("num_read_row_hits") / sumc("num_read_cmds") : 0.0);
    printf("dramsim3.average_read_latency=%.3f\n", histo_mean("read_latency"));
    printf("dramsim3.average_write_cmd_latency=%.3f\n", histo_mean("write_latency"));
    // DRAMsim3's energy (simple_stats.cc): sums of VDD x IDD x DRAM cycles x
    // devices, which it labels pJ; multiply by tCK in ns for pJ. Background
    // by rank state, summed over ranks; the rank-cycles in each state.
    const char* ekeys[] = {"act_energy", "read_energy", "write_energy", "ref_energy",
                           "refb_energy", "act_stb_energy", "pre_stb_energy",
                           "sref_energy", "total_energy"};
    for (auto k : ekeys) printf("dramsim3.%s=%.17g\n", k, sumd(k));
    printf("dramsim3.rank_active_cycles=%.17g\ndramsim3.all_bank_idle_cycles=%.17g\n",
           sumd("rank_active_cycles"), sumd("all_bank_idle_cycles"));
    printf("stats_json=%s\n", prefix_json.c_str());

    if (!per_req.empty()) {
        std::ofstream pr(per_req);
        pr << "# index arrival_cycle accept_cycle done_cycle\n";
        for (size_t i = 0; i < reqs.size(); i++)
            pr << i << " " << reqs[i].arrival << " " << reqs[i].accept << " "
               << reqs[i].done << "\n";
    }
    return finished ? 0 : 3;
}
