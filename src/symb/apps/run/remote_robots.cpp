#include "symb/apps/run/remote_robots.hpp"

#include <algorithm>
#include <sstream>

namespace symb::apps::run {

namespace {

double duration_s(kernel::Duration d) { return std::chrono::duration<double>(d).count(); }

}  // namespace

kernel::Result<std::unique_ptr<RemoteRobots>> RemoteRobots::attach(sim::ScenarioSession& session,
                                                                   const RemoteRobotsOptions& options,
                                                                   std::function<void(const std::string&)> on_event) {
  std::unique_ptr<RemoteRobots> r(new RemoteRobots());
  r->options_ = options;
  std::vector<sim::HilSplitWorld::Remote> remotes;
  std::vector<std::size_t> indices;
  for (const std::string& name : options.robots) {
    std::size_t index = session.robot_count();
    for (std::size_t i = 0; i < session.robot_count(); ++i)
      if (session.robot(i).name() == name) index = i;
    if (index == session.robot_count())
      return kernel::Error{"--remote: " + session.scenario().file + " has no robot '" + name + "'"};
    if (auto st = sim::HilSplitWorld::check(session.scenario(), index); !st)
      return kernel::Error{"--remote " + name + ": " + st.error()};
    indices.push_back(index);
  }
  auto links = io::DdsFrameLinks::create(options.dds);
  if (!links) return kernel::Error{"--bus dds: " + links.error()};
  r->links_ = std::move(links).value();
  for (std::size_t k = 0; k < indices.size(); ++k) {
    auto s = r->links_->stream(options.robots[k], kToRobot, kToWorld);
    if (!s) return kernel::Error{"--remote " + options.robots[k] + ": " + s.error()};
    r->streams_.push_back(*s);
    remotes.push_back({indices[k], *s});
  }
  auto world = sim::HilSplitWorld::create(session, std::move(remotes),
                                          {.answer_wait = options.answer_wait, .on_event = std::move(on_event)});
  if (!world) return kernel::Error{"--remote: " + world.error()};
  r->world_ = std::move(world).value();
  return r;
}

RemoteRobots::~RemoteRobots() {
  world_.reset();
  streams_.clear();
  links_.reset();
}

kernel::Status RemoteRobots::wait_for_robots(const std::function<bool()>& stopped) {
  return world_->wait_for_robots(options_.wait, stopped);
}

void RemoteRobots::finish(std::uint64_t steps) {
  world_->say_bye(steps);
  // A gone robot's reader would never acknowledge: flushing to it would only wait out the timeout.
  const auto stats = world_->stats();
  for (std::size_t k = 0; k < streams_.size(); ++k) {
    const bool gone = std::any_of(stats.begin(), stats.end(), [&](const sim::HilSplitRobotStats& s) {
      return s.gone && s.robot == options_.robots[k];
    });
    if (!gone) (void)streams_[k]->flush(std::chrono::seconds(2));
  }
  for (const auto& s : streams_) s->finish_sending();
}

std::string RemoteRobots::summary() const {
  std::ostringstream out;
  out << "bus: dds, domain " << options_.dds.domain << ", topics rt/" << options_.dds.prefix
      << "/<robot>/{to_robot,to_world}, lease " << duration_s(options_.dds.lease) << " s, answer wait "
      << duration_s(options_.answer_wait) << " s\n";
  const auto stats = world_->stats();
  out << "remote robots: " << stats.size() << " in other processes, lockstep, " << world_->gone() << " gone\n";
  for (const sim::HilSplitRobotStats& s : stats) out << "remote " << describe(s) << "\n";
  for (const sim::HilSplitRobotStats& s : stats)
    if (s.gone) out << "remote robot gone: " << s.robot << " at step " << s.gone_at << ": " << s.why << "\n";
  return out.str();
}

}  // namespace symb::apps::run
