#include "symb/apps/run/spike_recorder.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <fstream>
#include <sstream>

#include "symb/apps/text_file.hpp"
#include "symb/control/snn/aedat.hpp"
#include "symb/control/snn/network_layout.hpp"

namespace symb::apps::run {

namespace fs = std::filesystem;
using kernel::Error;

namespace {

std::string safe(std::string s) {
  for (char& c : s)
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_' || c == '.')) c = '_';
  return s;
}

}  // namespace

void SpikeRecorder::record(const os::ProbeSample& s) {
  std::lock_guard lock(mu_);
  Network& n = networks_[{std::string(s.node), std::string(s.task)}];
  const double time = std::chrono::duration<double>(s.time).count();
  if (s.channel == "layout") {
    auto layout = control::snn::layout_from_values(s.values);
    if (layout)
      n.layouts.emplace_back(time, std::move(layout).value());
    else if (n.bad_layout.empty())
      n.bad_layout = layout.error();
    return;
  }
  for (std::size_t i = 0; i + 1 < s.values.size(); i += 2) {
    const float ms = s.values[i], neuron = s.values[i + 1];
    if (!std::isfinite(ms) || !std::isfinite(neuron) || ms < 0 || neuron < 0 ||
        neuron > static_cast<float>(control::snn::kMaxNeuronAddress))
      continue;
    const auto id = static_cast<std::uint32_t>(neuron);
    const double t = static_cast<double>(ms) / 1000.0;
    ++n.spikes;
    n.max_neuron = std::max(n.max_neuron, id);
    n.last_time = std::max(n.last_time, t);
    if (t < kRasterSeconds) n.raster.push_back({t, id});
    if (n.events.size() < kMaxEvents)
      n.events.push_back({control::snn::aer_address(0, id),
                          static_cast<std::uint32_t>(static_cast<std::uint64_t>(std::llround(ms * 1000.0)))});
  }
}

std::uint64_t SpikeRecorder::spikes() const {
  std::lock_guard lock(mu_);
  std::uint64_t total = 0;
  for (const auto& [key, n] : networks_) total += n.spikes;
  return total;
}

kernel::Result<std::vector<fs::path>> SpikeRecorder::write(const fs::path& dir) const {
  std::lock_guard lock(mu_);
  std::vector<fs::path> files;
  if (networks_.empty()) return files;
  const fs::path out = dir / "spikes";
  std::error_code ec;
  fs::create_directories(out, ec);
  if (ec) return Error{"cannot create " + out.string() + ": " + ec.message()};
  for (const auto& [key, n] : networks_) {
    const std::string stem = safe(key.first) + "_" + safe(key.second);
    const std::string who = key.first + " / " + key.second;
    if (n.spikes > 0 || !n.layouts.empty()) {
      std::vector<std::string> comments = {"Symbricator symb run: spikes of " + who,
                                           "address = neuron index (module bits 0), timestamp = node time in us"};
      if (n.events.size() < n.spikes)
        comments.push_back("only the first " + std::to_string(n.events.size()) + " of " + std::to_string(n.spikes) +
                           " spikes");
      std::string aedat = control::snn::aedat_header(comments);
      control::snn::append_aedat_records(aedat, n.events);
      files.push_back(out / (stem + ".aedat"));
      if (auto st = write_file(files.back(), aedat); !st) return Error{st.error()};

      std::size_t rows = n.max_neuron + 1;
      if (!n.layouts.empty()) rows = std::max(rows, n.layouts.back().second.spec.neurons.size());
      std::ostringstream title;
      title << who << ": " << n.spikes << " spikes; raster of the first "
            << static_cast<int>(std::min(kRasterSeconds, std::ceil(n.last_time))) << " s";
      files.push_back(out / (stem + "_raster.svg"));
      if (auto st = write_file(files.back(), raster_svg(n.raster, rows, title.str())); !st) return Error{st.error()};
    }
    for (std::size_t k = 0; k < n.layouts.size(); ++k) {
      const auto& [time, net] = n.layouts[k];
      std::ostringstream title;
      title << who << ": " << net.spec.neurons.size() << " neurons, " << net.spec.synapses.size() << " synapses";
      if (k > 0) title << " (grown at " << std::fixed << time << " s)";
      files.push_back(out / (stem + "_network" + (k == 0 ? std::string() : "_" + std::to_string(k + 1)) + ".svg"));
      if (auto st = write_file(files.back(), network_svg(net, title.str())); !st) return Error{st.error()};
    }
  }
  return files;
}

}  // namespace symb::apps::run
