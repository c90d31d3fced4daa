// `vlab camera` end to end: it serves a video file the test writes with
// cv::VideoWriter, a CameraClient receives its frames (compared with the
// file's own frames within JPEG tolerance), SIGINT stops it cleanly, and bad
// input is one line and exit code 2.
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include "bridge/bridge_camera_client.h"
#include "test_util.h"

namespace vlab::testing {
namespace {

constexpr int kW = 160, kH = 120, kFileFrames = 12;

/// `vlab camera ARGS` as a child; stdout/stderr into files of `dir`.
class CameraProcess {
 public:
  CameraProcess(const std::string& args, const std::string& dir)
      : out_(dir + "/camera.out"), err_(dir + "/camera.err") {
    const std::string cmd = "cd '" VLAB_SOURCE_DIR "' && exec '" VLAB_BINARY_DIR "/vlab' camera " + args + " >'" +
                            out_ + "' 2>'" + err_ + "' </dev/null";
    pid_ = fork();
    if (pid_ == 0) {
      execl("/bin/sh", "sh", "-c", cmd.c_str(), static_cast<char*>(nullptr));
      _exit(127);
    }
  }
  ~CameraProcess() {
    if (pid_ > 0 && !reaped_) {
      kill(pid_, SIGKILL);
      waitpid(pid_, nullptr, 0);
    }
  }
  bool WaitStarted(double timeout_s = 20) {
    for (int i = 0; i < timeout_s * 100; ++i) {
      if (ReadFile(out_).find("vlab camera: '") != std::string::npos) return true;
      if (Exited()) return false;
      usleep(10000);
    }
    return false;
  }
  void Signal(int sig) { kill(pid_, sig); }
  /// Waits for the exit (kills it after timeout_s); its exit code, -1 if killed.
  int Wait(double timeout_s = 20) {
    for (int i = 0; i < timeout_s * 100 && !Exited(); ++i) usleep(10000);
    if (!reaped_) {
      kill(pid_, SIGKILL);
      waitpid(pid_, nullptr, 0);
      reaped_ = true;
      return -1;
    }
    return code_;
  }
  std::string Output() const { return ReadFile(out_); }
  std::string Errors() const { return ReadFile(err_); }

 private:
  bool Exited() {
    int status = 0;
    if (!reaped_ && waitpid(pid_, &status, WNOHANG) == pid_) {
      reaped_ = true;
      code_ = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    }
    return reaped_;
  }
  pid_t pid_ = -1;
  bool reaped_ = false;
  int code_ = -1;
  std::string out_, err_;
};

int FreePort() { return bridge::UdpSocket::Bind("127.0.0.1", 0)->local_port(); }

// frame i: smooth, different per frame (a moving gradient and a bright square)
cv::Mat FileFrame(int i) {
  cv::Mat bgr(kH, kW, CV_8UC3);
  for (int y = 0; y < kH; ++y) {
    for (int x = 0; x < kW; ++x) {
      bgr.at<cv::Vec3b>(y, x) =
          cv::Vec3b(static_cast<uchar>(x / 2 + 10 * i), static_cast<uchar>(y * 2), static_cast<uchar>(20 * i));
    }
  }
  cv::rectangle(bgr, cv::Rect(10 + 8 * i, 40, 24, 24), cv::Scalar(255, 255, 255), cv::FILLED);
  return bgr;
}

// writes the clip; returns its frames as decoded by OpenCV (RGB), the reference
std::vector<cv::Mat> WriteClip(const std::string& path) {
  cv::VideoWriter writer(path, cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), 20, cv::Size(kW, kH));
  EXPECT_TRUE(writer.isOpened());
  for (int i = 0; i < kFileFrames; ++i) writer.write(FileFrame(i));
  writer.release();
  cv::VideoCapture read(path);
  std::vector<cv::Mat> frames;
  cv::Mat bgr, rgb;
  while (read.read(bgr)) {
    cv::cvtColor(bgr, rgb, cv::COLOR_BGR2RGB);
    frames.push_back(rgb.clone());
  }
  EXPECT_EQ(frames.size(), static_cast<std::size_t>(kFileFrames));
  return frames;
}

TEST(CameraCliTest, ServesAVideoFileThatAClientReceives) {
  TempDir dir;
  const std::string clip = dir / "clip.avi";
  const std::vector<cv::Mat> reference = WriteClip(clip);
  const int port = FreePort();
  CameraProcess camera("--source '" + clip + "' --port " + std::to_string(port) +
                           " --loop --fps 50 --name desk --pose 0.5,0,1.2,0,1,0,0",
                       dir.path());
  ASSERT_TRUE(camera.WaitStarted()) << camera.Errors();
  EXPECT_NE(camera.Output().find("'desk' from " + clip), std::string::npos) << camera.Output();

  bridge::CameraClient client = bridge::CameraClient::Connect("127.0.0.1", port);
  const nlohmann::json& j = client.describe();
  EXPECT_EQ(j["server"], "vlab camera");
  EXPECT_EQ(j["source"], clip);
  EXPECT_EQ(j["clock"], "realtime");
  EXPECT_EQ(j["encoding"], "jpeg");
  EXPECT_EQ(j["pose"], "fixed");
  EXPECT_EQ(client.fps(), 50);
  EXPECT_EQ(client.width(), kW);
  EXPECT_EQ(client.height(), kH);
  EXPECT_EQ(client.calibration().source, "estimated");  // a 60 deg horizontal field of view
  EXPECT_NEAR(client.calibration().fx, 80 / std::tan(30 * M_PI / 180), 1e-9);
  EXPECT_EQ(client.calibration().cx, 79.5);

  // a whole pass of the file and more: each frame is the file's frame (id mod length)
  bridge::CameraClient::Frame f;
  std::int64_t last = -1;
  double worst_mean = 0;
  for (int n = 0; n < kFileFrames + 6; ++n) {
    client.Receive(2.0, &f);
    ASSERT_GT(f.id, last);
    last = f.id;
    ASSERT_EQ(f.rgb.size(), 3u * kW * kH);
    const cv::Mat got(kH, kW, CV_8UC3, f.rgb.data());
    const cv::Mat& want = reference[static_cast<std::size_t>(f.id % kFileFrames)];
    const double mean = cv::norm(got, want, cv::NORM_L1) / (3.0 * kW * kH);
    worst_mean = std::max(worst_mean, mean);
    EXPECT_LT(mean, 3.0) << "frame " << f.id;
    // and not another frame of the file
    const cv::Mat& other = reference[static_cast<std::size_t>((f.id + 1) % kFileFrames)];
    EXPECT_GT(cv::norm(got, other, cv::NORM_L1) / (3.0 * kW * kH), 2 * mean + 1) << "frame " << f.id;
    EXPECT_TRUE(f.pose.valid);
    EXPECT_EQ(f.pose.p_WC, Eigen::Vector3d(0.5, 0, 1.2));
    EXPECT_EQ(f.pose.q_WC.x(), 1.0);
  }
  std::printf("vlab camera: %d frames compared with the file's, worst mean |error| %.2f grey levels\n", kFileFrames + 6,
              worst_mean);
  camera.Signal(SIGINT);
  EXPECT_EQ(camera.Wait(), 0) << camera.Errors();
  EXPECT_NE(camera.Output().find("interrupted"), std::string::npos) << camera.Output();
  EXPECT_EQ(camera.Errors(), "");
}

TEST(CameraCliTest, StopsAtTheEndOfTheFileOrAfterFrames) {
  TempDir dir;
  const std::string clip = dir / "clip.avi";
  WriteClip(clip);
  CameraProcess all("--source '" + clip + "' --port 0 --fps 200 --encoding raw", dir.path());
  EXPECT_EQ(all.Wait(), 0) << all.Errors();
  EXPECT_NE(all.Output().find("vlab camera: 12 frames"), std::string::npos) << all.Output();
  EXPECT_NE(all.Output().find("end of file"), std::string::npos) << all.Output();
  const ProcessResult five = RunVlab("camera --source '" + clip + "' --port 0 --fps 200 --loop --frames 30", 30);
  EXPECT_EQ(five.exit_code, 0) << five.err;
  EXPECT_NE(five.out.find("vlab camera: 30 frames"), std::string::npos) << five.out;
  EXPECT_NE(five.out.find("--frames reached"), std::string::npos) << five.out;
}

// one line on stderr naming the problem, exit code 2
void ExpectBadInput(const std::string& args, const std::string& needle) {
  const ProcessResult r = RunVlab("camera " + args, 30);
  EXPECT_EQ(r.exit_code, 2) << args << "\n" << r.err;
  EXPECT_NE(r.err.find(needle), std::string::npos) << args << "\n" << r.err;
  EXPECT_EQ(Lines(r.err).size(), 1u) << r.err;
  EXPECT_EQ(r.out, "") << "nothing served";
}

TEST(CameraCliTest, UnreadableSourceIsOneLineAndExitCode2) {
  TempDir dir;
  ExpectBadInput("--source '" + (dir / "missing.avi") + "'", "video source '" + (dir / "missing.avi") + "': no such");
  WriteFile(dir / "notes.avi", "this is not a video\n");
  ExpectBadInput("--source '" + (dir / "notes.avi") + "'", "not a video file OpenCV can read");
  ExpectBadInput("--source '" + dir.path() + "'", "neither a video file nor a V4L2 device");
  ExpectBadInput("--source /dev/video97", "no such file or device");
  // the source is checked before anything is bound: a bad address is not even looked at
  ExpectBadInput("--source '" + (dir / "missing.avi") + "' --bind 999.1.1.1", "missing.avi");
}

TEST(CameraCliTest, BadOptionsAreOneLineAndExitCode2) {
  TempDir dir;
  const std::string clip = dir / "clip.avi";
  WriteClip(clip);
  const std::string src = "--source '" + clip + "' ";
  ExpectBadInput(src + "--pose 1,2,3,1,0,0", "expected 7 comma-separated numbers");
  ExpectBadInput(src + "--pose 1,2,3,2,0,0,0", "unit length");
  ExpectBadInput(src + "--distortion 0.1,x,0,0", "'x' is not a number");
  ExpectBadInput(src + "--fx 500", "go together");
  ExpectBadInput(src + "--width 320", "go together");
  ExpectBadInput(src + "--fps -5", "--fps");
  ExpectBadInput(src + "--jpeg-quality 0", "--jpeg-quality");
  ExpectBadInput(src + "--encoding png", "--encoding");
  ExpectBadInput(src + "--chunk-bytes 70000", "--chunk-bytes");
  ExpectBadInput(src + "--bind 999.1.1.1", "999.1.1.1");
  ExpectBadInput(src + "--frames 0", "--frames");
  auto busy = bridge::UdpSocket::Bind("127.0.0.1", 0);
  ExpectBadInput(src + "--port " + std::to_string(busy->local_port()), "cannot bind");
}

}  // namespace
}  // namespace vlab::testing
