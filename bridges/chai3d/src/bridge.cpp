#include "bridge.h"

#include <algorithm>
#include <arpa/inet.h>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fcntl.h>
#include <netdb.h>
#include <sys/select.h>
#include <sys/socket.h>
#include <thread>
#include <unistd.h>
#include <vector>

#include "protocol.h"

namespace coiffure {
namespace {

using Clock = std::chrono::steady_clock;
using Vec = std::array<double, 3>;
using Mat = std::array<double, 9>;  // row-major

// CHAI3D's frame (x towards the user, y right, z up) to the protocol's device frame (x right, y away from
// the user, z up): (x, y, z) -> (y, -x, z).
const Mat kM = {0, 1, 0, -1, 0, 0, 0, 0, 1};
// The tool's rest orientation: the comb held from behind the head (tool x along -x, tool y along -z, tool z
// along -y: teeth into the head, strokes downwards), as in examples/scenarios/live-comb.toml.
const Mat kRest = {-1, 0, 0, 0, 0, -1, 0, -1, 0};

Vec mul(const Mat& a, const Vec& v) {
    return {a[0] * v[0] + a[1] * v[1] + a[2] * v[2], a[3] * v[0] + a[4] * v[1] + a[5] * v[2], a[6] * v[0] + a[7] * v[1] + a[8] * v[2]};
}
Vec mul_t(const Mat& a, const Vec& v) {
    return {a[0] * v[0] + a[3] * v[1] + a[6] * v[2], a[1] * v[0] + a[4] * v[1] + a[7] * v[2], a[2] * v[0] + a[5] * v[1] + a[8] * v[2]};
}
Mat mul(const Mat& a, const Mat& b) {
    Mat c{};
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
            for (int k = 0; k < 3; ++k) c[3 * i + j] += a[3 * i + k] * b[3 * k + j];
    return c;
}
Mat transpose(const Mat& a) { return {a[0], a[3], a[6], a[1], a[4], a[7], a[2], a[5], a[8]}; }
double norm(const Vec& v) { return std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]); }

double quantile(std::vector<double> v, double q) {
    if (v.empty()) return 0.0;
    std::sort(v.begin(), v.end());
    std::size_t i = static_cast<std::size_t>(std::ceil(q * v.size()));
    return v[std::min(std::max<std::size_t>(i, 1), v.size()) - 1];
}

int open_socket(const Options& o) {
    addrinfo hints{};
    hints.ai_family = AF_INET;
    hints.ai_socktype = SOCK_DGRAM;
    addrinfo* res = nullptr;
    std::string port = std::to_string(o.port);
    if (getaddrinfo(o.host.c_str(), port.c_str(), &hints, &res) != 0 || !res) {
        std::fprintf(stderr, "bridge: cannot resolve %s\n", o.host.c_str());
        return -1;
    }
    int fd = socket(res->ai_family, res->ai_socktype, res->ai_protocol);
    if (fd < 0 || connect(fd, res->ai_addr, res->ai_addrlen) != 0) {
        std::fprintf(stderr, "bridge: cannot open a UDP socket to %s:%d: %s\n", o.host.c_str(), o.port, std::strerror(errno));
        freeaddrinfo(res);
        if (fd >= 0) close(fd);
        return -1;
    }
    freeaddrinfo(res);
    fcntl(fd, F_SETFL, fcntl(fd, F_GETFL, 0) | O_NONBLOCK);
    return fd;
}

}  // namespace

int run(Device& device, const Options& o, volatile bool& stop, Stats& stats) {
    std::string error;
    if (!device.open(error)) {
        std::fprintf(stderr, "bridge: %s\n", error.c_str());
        return 1;
    }
    DeviceInfo info = device.info();
    const double max_force = o.max_force > 0.0 ? std::min(o.max_force, info.max_force) : info.max_force;
    int fd = open_socket(o);
    if (fd < 0) {
        device.close();
        return 1;
    }
    std::FILE* log = o.log.empty() ? nullptr : std::fopen(o.log.c_str(), "w");
    if (log) std::fprintf(log, "t,x,y,z,fx,fy,fz,ramp,latency_us,tx,ty,tz\n");
    std::printf("bridge: %s (%.1f N) -> udp:%s:%d at %.0f Hz\n", info.name.c_str(), max_force, o.host.c_str(), o.port, o.rate);
    std::fflush(stdout);

    const auto period = std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(1.0 / o.rate));
    const auto start = Clock::now();
    std::vector<Clock::time_point> sent_at(4096);  // by sequence number modulo 4096
    std::vector<double> rtt, periods;
    rtt.reserve(1 << 16);
    periods.reserve(1 << 16);
    Vec force{0, 0, 0};           // latest force received, device frame of the protocol, N
    Vec torque{0, 0, 0};          // latest torque received, N m
    double answered_at = -1.0;    // s, time of the latest answer
    double connected_at = -1.0;   // s, start of the current run of answers (the ramp's origin)
    std::uint32_t seq = 0;
    Clock::time_point last_send{};
    for (long long n = 0; !stop; ++n) {
        const auto deadline = start + period * n;  // signed: deadline - now may be negative
        const double t_deadline = std::chrono::duration<double>(deadline - start).count();
        if (o.duration > 0.0 && t_deadline > o.duration) break;
        // Answers: the latest force; the round trip of each, timed when it arrives (the loop waits for the
        // deadline on the socket, then spins the last 200 us for precision).
        unsigned char buf[256];
        double latency = std::nan("");
        auto drain = [&]() {
            for (;;) {
                ssize_t got = recv(fd, buf, sizeof buf, 0);
                if (got < 0) break;
                const auto at = Clock::now();
                const double ta = std::chrono::duration<double>(at - start).count();
                Force f;
                if (!decode_force(buf, static_cast<std::size_t>(got), f)) {
                    ++stats.malformed;
                    continue;
                }
                ++stats.answered;
                if (f.flags & kFlagRejected) ++stats.rejected;
                if (seq - f.seq < 4096) {
                    latency = std::chrono::duration<double>(at - sent_at[f.seq % 4096]).count();
                    rtt.push_back(latency);
                }
                bool finite = std::isfinite(f.force[0]) && std::isfinite(f.force[1]) && std::isfinite(f.force[2]);
                force = finite ? f.force : Vec{0, 0, 0};
                bool finite_t = std::isfinite(f.torque[0]) && std::isfinite(f.torque[1]) && std::isfinite(f.torque[2]);
                torque = finite_t ? f.torque : Vec{0, 0, 0};
                if (answered_at < 0.0 || ta - answered_at > o.timeout) connected_at = ta;
                answered_at = ta;
            }
        };
        for (;;) {
            drain();
            auto left = std::chrono::duration_cast<std::chrono::microseconds>(deadline - Clock::now()).count();
            if (left <= 200) break;
            fd_set set;
            FD_ZERO(&set);
            FD_SET(fd, &set);
            timeval tv{static_cast<time_t>((left - 200) / 1000000), static_cast<suseconds_t>((left - 200) % 1000000)};
            select(fd + 1, &set, nullptr, nullptr, &tv);
        }
        while (Clock::now() < deadline) {
        }
        drain();
        const auto now = Clock::now();
        const double t = std::chrono::duration<double>(now - start).count();
        // Zero force when the answers stopped (the ramp starts again when they return), else ramped and clamped.
        double ramp = 0.0;
        Vec applied{0, 0, 0}, applied_t{0, 0, 0};
        if (answered_at >= 0.0 && t - answered_at <= o.timeout) {
            ramp = o.ramp > 0.0 ? std::min(1.0, (t - connected_at) / o.ramp) : 1.0;
            double scale = ramp;
            double m = norm(force) * ramp;
            if (m > max_force) scale *= max_force / m;
            applied = {force[0] * scale, force[1] * scale, force[2] * scale};
            // The torque likewise, within the device's own torque limit (0 on a 3-DOF device: none).
            double scale_t = ramp;
            double mt = norm(torque) * ramp;
            if (mt > info.max_torque) scale_t = mt > 0.0 ? scale_t * info.max_torque / mt : 0.0;
            applied_t = {torque[0] * scale_t, torque[1] * scale_t, torque[2] * scale_t};
        } else if (answered_at >= 0.0) {
            ++stats.stale;
        }
        device.set_force_and_torque(mul_t(kM, applied), mul_t(kM, applied_t));  // protocol frame -> CHAI3D frame
        stats.max_applied = std::max(stats.max_applied, norm(applied));

        // The pose, in the protocol's device frame.
        Vec p;
        Mat r;
        std::uint32_t buttons = 0;
        device.read(t, p, r, buttons);
        Pose pose;
        pose.seq = ++seq;
        pose.time = t;
        pose.position = mul(kM, p);
        pose.rotation = mul(mul(kM, r), transpose(kM));
        if (o.tool_rotation) pose.rotation = mul(pose.rotation, kRest);
        pose.buttons = buttons;
        auto bytes = encode_pose(pose);
        sent_at[pose.seq % 4096] = Clock::now();
        if (send(fd, bytes.data(), bytes.size(), 0) == static_cast<ssize_t>(bytes.size())) ++stats.sent;
        if (n > 0) periods.push_back(std::chrono::duration<double>(now - last_send).count());
        last_send = now;
        if (log)
            std::fprintf(log, "%.6f,%.7f,%.7f,%.7f,%.6f,%.6f,%.6f,%.6f,%.1f,%.6f,%.6f,%.6f\n", t, pose.position[0], pose.position[1], pose.position[2], applied[0], applied[1], applied[2], ramp,
                         latency * 1e6, applied_t[0], applied_t[1], applied_t[2]);
    }
    device.set_force({0, 0, 0});
    device.close();
    close(fd);
    if (log) std::fclose(log);
    stats.rtt_p50 = quantile(rtt, 0.5);
    stats.rtt_p99 = quantile(rtt, 0.99);
    stats.rtt_max = quantile(rtt, 1.0);
    stats.period_p99 = quantile(periods, 0.99);
    return 0;
}

}  // namespace coiffure
