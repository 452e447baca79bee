// coiffure-chai3d-bridge: a haptic device (through CHAI3D, or simulated) drives `coiffure serve --device`.
//   coiffure-chai3d-bridge [--server HOST:PORT] [--rate HZ] [--duration S] [--ramp S] [--timeout-ms MS]
//                          [--max-force N] [--no-tool-rotation] [--log FILE.csv]
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>

#include "bridge.h"

namespace {
volatile bool g_stop = false;
void on_signal(int) { g_stop = true; }

bool number(const char* s, double& out) {
    char* end = nullptr;
    out = std::strtod(s, &end);
    return end && *end == '\0' && end != s;
}

int usage(const char* why) {
    std::fprintf(stderr, "coiffure-chai3d-bridge: %s\nusage: coiffure-chai3d-bridge [--server HOST:PORT] [--rate HZ] [--duration S] [--ramp S] [--timeout-ms MS] [--max-force N] [--no-tool-rotation] [--log FILE.csv]\n", why);
    return 2;
}
}  // namespace

int main(int argc, char** argv) {
    coiffure::Options o;
    for (int i = 1; i < argc; ++i) {
        std::string a = argv[i];
        auto value = [&](double& out, double lo, double hi) {
            if (i + 1 >= argc || !number(argv[++i], out) || !(out >= lo && out <= hi)) return false;
            return true;
        };
        double v = 0.0;
        if (a == "--server" && i + 1 < argc) {
            std::string s = argv[++i];
            auto colon = s.rfind(':');
            if (colon == std::string::npos || !number(s.c_str() + colon + 1, v) || v < 1 || v > 65535) return usage("--server needs HOST:PORT");
            o.host = s.substr(0, colon);
            o.port = static_cast<int>(v);
        } else if (a == "--rate") {
            if (!value(o.rate, 1.0, 10000.0)) return usage("--rate needs a number of Hz in [1, 10000]");
        } else if (a == "--duration") {
            if (!value(o.duration, 0.0, 1e9)) return usage("--duration needs seconds >= 0");
        } else if (a == "--ramp") {
            if (!value(o.ramp, 0.0, 60.0)) return usage("--ramp needs seconds in [0, 60]");
        } else if (a == "--timeout-ms") {
            if (!value(v, 1.0, 10000.0)) return usage("--timeout-ms needs milliseconds in [1, 10000]");
            o.timeout = v * 1e-3;
        } else if (a == "--max-force") {
            if (!value(o.max_force, 0.0, 1000.0)) return usage("--max-force needs N in [0, 1000]");
        } else if (a == "--no-tool-rotation") {
            o.tool_rotation = false;
        } else if (a == "--log" && i + 1 < argc) {
            o.log = argv[++i];
        } else {
            return usage(("unknown or incomplete option " + a).c_str());
        }
    }
    std::signal(SIGINT, on_signal);
    std::signal(SIGTERM, on_signal);
    auto device = coiffure::make_device();
    coiffure::Stats s;
    int rc = coiffure::run(*device, o, g_stop, s);
    if (rc == 0) {
        std::printf("bridge: sent %llu, answered %llu (%.1f %%), rejected %llu, malformed %llu, stale steps %llu, round trip p50 %.0f us p99 %.0f us max %.0f us, send period p99 %.0f us, largest force applied %.3f N\n",
                    (unsigned long long)s.sent, (unsigned long long)s.answered, s.sent ? 100.0 * s.answered / s.sent : 0.0, (unsigned long long)s.rejected,
                    (unsigned long long)s.malformed, (unsigned long long)s.stale, s.rtt_p50 * 1e6, s.rtt_p99 * 1e6, s.rtt_max * 1e6, s.period_p99 * 1e6, s.max_applied);
    }
    return rc;
}
