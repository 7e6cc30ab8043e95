#include "symb/io/stdio_stream.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <atomic>
#include <thread>

#include <gtest/gtest.h>

#include "symb/io/pty_pair.hpp"

#include "io_test_support.hpp"

namespace symb::io {
namespace {

using namespace std::chrono_literals;
using testing::read_exactly;

// A pipe whose ends the test closes itself (StdioStream only borrows descriptors).
struct Pipe {
  int fd[2] = {-1, -1};
  Pipe() {
    if (::pipe2(fd, O_CLOEXEC) != 0) ADD_FAILURE() << "pipe2 failed";
  }
  ~Pipe() {
    for (int f : fd)
      if (f >= 0) ::close(f);
  }
  void close_write() {
    ::close(fd[1]);
    fd[1] = -1;
  }
};

TEST(StdioStream, ReadsAndWritesBorrowedDescriptors) {
  Pipe in, out;
  StdioStream s("console", in.fd[0], out.fd[1]);
  ASSERT_TRUE(s.is_open());
  EXPECT_FALSE(s.input_is_tty());
  EXPECT_FALSE(s.output_is_tty());
  auto info = s.ioctl("info");
  ASSERT_TRUE(info);
  EXPECT_NE(info->find("in_tty=false"), std::string::npos) << *info;

  // Input: text through the stream operators.
  const std::string typed = "set speed 0.25\n";
  ASSERT_EQ(::write(in.fd[1], typed.data(), typed.size()), static_cast<ssize_t>(typed.size()));
  auto line = s.read_line(testing::kDeadline);
  ASSERT_TRUE(line && *line);
  EXPECT_EQ(**line, "set speed 0.25");

  // Output: more than a pipe holds, read on the other side while it is written.
  std::vector<std::byte> big(200000);
  for (std::size_t i = 0; i < big.size(); ++i) big[i] = static_cast<std::byte>(i % 251);
  StdioStream reader_side("peer", out.fd[0], -1);
  testing::Writer w(s, big);
  EXPECT_EQ(read_exactly(reader_side, big.size()), big);
  EXPECT_EQ(w.join(), "");
  s << "ok " << 3 << '\n';
  EXPECT_EQ(read_exactly(reader_side, 5).size(), 5u);

  // End of input is an error and closes the stream for reading; the descriptors stay open.
  in.close_write();
  std::byte buf[8];
  auto eof = s.read_some(buf, testing::kDeadline);
  ASSERT_FALSE(eof);
  EXPECT_NE(eof.error().find("end of stream"), std::string::npos) << eof.error();
  EXPECT_FALSE(s.is_open());
  EXPECT_TRUE(s.input_ended());
  // Only the input ended: the replies to what was read still go out (a script piped into a shell).
  ASSERT_TRUE(s.write_all(as_bytes("reply\n")).ok());
  EXPECT_EQ(read_exactly(reader_side, 6).size(), 6u);
  EXPECT_FALSE(s.read_some(buf, 10ms));  // and reading stays over, at once
  s.close();
  EXPECT_NE(::fcntl(out.fd[1], F_GETFD), -1) << "a borrowed descriptor was closed";
  EXPECT_TRUE(s.open());
}

TEST(StdioStream, WritingToAPipeNobodyReadsIsAnErrorNotSigpipe) {
  Pipe out;
  StdioStream s("console", -1, out.fd[1]);
  ::close(out.fd[0]);
  out.fd[0] = -1;
  auto st = s.write_all(as_bytes("into the void"));
  ASSERT_FALSE(st);
  EXPECT_NE(st.error().find("gone"), std::string::npos) << st.error();
  EXPECT_FALSE(s.is_open());
}

TEST(StdioStream, CloseWakesAReaderWithoutClosingTheDescriptor) {
  Pipe in;
  StdioStream s("console", in.fd[0], -1);
  std::atomic<pid_t> tid{0};
  std::string error;
  std::thread reader([&] {
    tid = testing::this_thread_tid();
    std::byte buf[8];
    auto r = s.read_some(buf, 60s);
    if (!r) error = r.error();
  });
  ASSERT_TRUE(symb::testing::eventually([&] { return tid.load() != 0 && testing::thread_sleeping(tid.load()); }));
  s.close();
  reader.join();
  EXPECT_NE(error.find("closed"), std::string::npos) << error;
  EXPECT_NE(::fcntl(in.fd[0], F_GETFD), -1);
}

TEST(StdioStream, DetectsATerminalAndDefaultsToStandardDescriptors) {
  auto pty = PtyPair::open("tty");
  ASSERT_TRUE(pty) << pty.error();
  const int fd = ::open(pty->slave_path.c_str(), O_RDWR | O_NOCTTY | O_CLOEXEC);
  ASSERT_GE(fd, 0);
  {
    StdioStream s("terminal", fd, fd);
    EXPECT_TRUE(s.input_is_tty());
    EXPECT_TRUE(s.output_is_tty());
    ASSERT_TRUE(s.write_all(as_bytes("hi")));
    EXPECT_EQ(read_exactly(*pty->master, 2).size(), 2u);
  }
  ::close(fd);

  StdioStream std_io;
  EXPECT_EQ(std_io.name(), "stdio");
  EXPECT_EQ(std_io.input_is_tty(), ::isatty(0) == 1);
  EXPECT_EQ(std_io.output_is_tty(), ::isatty(1) == 1);
  auto info = std_io.ioctl("info");
  ASSERT_TRUE(info);
  EXPECT_NE(info->find("in_fd=0"), std::string::npos) << *info;
  EXPECT_NE(info->find("out_fd=1"), std::string::npos) << *info;

  StdioStream bad("bad", 987, 988);
  EXPECT_FALSE(bad.is_open());
  auto st = bad.open();
  ASSERT_FALSE(st);
  EXPECT_NE(st.error().find("bad descriptor"), std::string::npos) << st.error();
}

}  // namespace
}  // namespace symb::io
