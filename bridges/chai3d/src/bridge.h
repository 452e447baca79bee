// The bridge's loop: read the device at a fixed rate, send CFP1 poses, apply the CFF1 forces received.
#pragma once
#include <cstdint>
#include <string>

#include "device.h"

namespace coiffure {

struct Options {
    std::string host = "127.0.0.1";  // where `coiffure serve --device udp:PORT` listens
    int port = 5555;
    double rate = 1000.0;    // poses per second, Hz
    double duration = 0.0;   // s; 0: until Ctrl-C
    double ramp = 1.0;       // safety ramp: the force grows from 0 to full over this time after (re)connecting, s
    double timeout = 0.05;   // no answer for this long: zero force, and the ramp starts again, s
    double max_force = 0.0;  // local clamp, N; 0: the device's own limit
    bool tool_rotation = true;  // turn the device's frame into the comb's held from behind the head (docs)
    std::string log;         // CSV t,x,y,z,fx,fy,fz,ramp,latency_us (device frame of the protocol)
};

struct Stats {
    std::uint64_t sent = 0, answered = 0, rejected = 0, malformed = 0, stale = 0;
    double rtt_p50 = 0.0, rtt_p99 = 0.0, rtt_max = 0.0;  // s
    double max_applied = 0.0;                             // N
    double period_p99 = 0.0;                              // s, time between two sends
};

// Runs until `duration` or until `stop` is set; returns 0, or 1 with a message on stderr.
int run(Device& device, const Options& o, volatile bool& stop, Stats& stats);

}  // namespace coiffure
