// Image files read as gray (io/image_file.hpp). A JPEG or PNG cut short anywhere before its end
// (EOI marker, IEND chunk) is an error naming the file, not an image whose rest libjpeg fills gray
// or a failure with libpng's own line; complete ones (JPEG: baseline, progressive, with restart
// markers, colour; PNG: gray and colour; either with bytes after its end; the repository's real
// photos) read as OpenCV reads them.
#include <gtest/gtest.h>

#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "netvmo/pipeline/error.hpp"
#include "netvmo/pipeline/io/image_file.hpp"
#include "synth.hpp"
#include "test_util.hpp"

namespace netvmo {
namespace {
namespace fs = std::filesystem;

// A dark square on uniform noise: the entropy-coded data holds every byte value, FF 00 (a
// stuffed FF) included.
cv::Mat picture(int channels) {
  cv::Mat m(96, 128, CV_8UC(channels));
  cv::RNG rng(7);
  rng.fill(m, cv::RNG::UNIFORM, 0, 256);
  cv::rectangle(m, {30, 20}, {90, 70}, cv::Scalar::all(0), cv::FILLED);
  return m;
}

std::vector<std::uint8_t> encode(const cv::Mat& m, const std::vector<int>& params) {
  std::vector<std::uint8_t> out;
  EXPECT_TRUE(cv::imencode(".jpg", m, out, params));
  return out;
}

void write(const fs::path& p, const std::vector<std::uint8_t>& bytes) {
  std::ofstream(p, std::ios::binary)
      .write(reinterpret_cast<const char*>(bytes.data()),
             static_cast<std::streamsize>(bytes.size()));
}

// The smallest length below the whole that jpeg_cut_short takes for complete, or 0 if there is
// none: every cut must be found.
size_t first_cut_missed(const std::vector<std::uint8_t>& b) {
  for (size_t n = 2; n < b.size(); ++n)
    if (io::jpeg_cut_short(b.data(), n).empty()) return n;
  return 0;
}

TEST(ImageFile, JpegCutShortAnywhereIsFound) {
  const struct {
    const char* name;
    int channels;
    std::vector<int> params;
  } kinds[] = {
      {"baseline", 1, {cv::IMWRITE_JPEG_QUALITY, 90}},
      {"progressive", 1, {cv::IMWRITE_JPEG_PROGRESSIVE, 1}},
      {"restart markers", 1, {cv::IMWRITE_JPEG_RST_INTERVAL, 2}},
      {"colour 4:2:0", 3, {cv::IMWRITE_JPEG_QUALITY, 75}},
  };
  for (const auto& k : kinds) {
    std::vector<std::uint8_t> b = encode(picture(k.channels), k.params);
    ASSERT_GT(b.size(), 1000u) << k.name;
    EXPECT_EQ(io::jpeg_cut_short(b.data(), b.size()), "") << k.name;
    EXPECT_EQ(first_cut_missed(b), 0u) << k.name << ": a cut at this byte was not found";
    // The message says where.
    const std::string why = io::jpeg_cut_short(b.data(), b.size() / 2);
    EXPECT_NE(why.find("byte " + std::to_string(b.size() / 2)), std::string::npos) << why;
    EXPECT_NE(why.find("EOI"), std::string::npos) << why;
    // Bytes after the EOI (a camera's trailer) are not the image's.
    const std::string trailer = "trailer \xFF\xD8\xFF";
    b.insert(b.end(), trailer.begin(), trailer.end());
    EXPECT_EQ(io::jpeg_cut_short(b.data(), b.size()), "") << k.name << " with a trailer";
  }
  // Not a JPEG: nothing to say.
  std::vector<std::uint8_t> png;
  cv::imencode(".png", picture(1), png);
  EXPECT_EQ(io::jpeg_cut_short(png.data(), png.size() / 2), "");
  EXPECT_EQ(io::jpeg_cut_short(png.data(), 0), "");
}

TEST(ImageFile, PngCutShortAnywhereIsFound) {
  for (int channels : {1, 3}) {
    std::vector<std::uint8_t> b;
    ASSERT_TRUE(cv::imencode(".png", picture(channels), b));
    EXPECT_EQ(io::png_cut_short(b.data(), b.size()), "") << channels;
    size_t missed = 0;  // every cut from the end of the signature on must be found
    for (size_t n = 8; n < b.size() && !missed; ++n)
      if (io::png_cut_short(b.data(), n).empty()) missed = n;
    EXPECT_EQ(missed, 0u) << channels << " channels: a cut at this byte was not found";
    const std::string why = io::image_cut_short(b.data(), b.size() / 2);
    EXPECT_EQ(why.rfind("PNG cut short: the data ends at byte " + std::to_string(b.size() / 2), 0),
              0u)
        << why;
    EXPECT_NE(why.find("IDAT"), std::string::npos) << why;
    b.insert(b.end(), {'t', 'r', 'a', 'i', 'l'});
    EXPECT_EQ(io::png_cut_short(b.data(), b.size()), "") << channels << " with a trailer";
  }
  // A JPEG is not a PNG.
  const std::vector<std::uint8_t> jpeg = encode(picture(1), {});
  EXPECT_EQ(io::png_cut_short(jpeg.data(), jpeg.size() / 2), "");
  EXPECT_EQ(io::image_cut_short(jpeg.data(), jpeg.size() / 2).rfind("JPEG cut short: ", 0), 0u);
}

TEST(ImageFile, ReadGrayImageRefusesACutImageNamingTheFile) {
  const fs::path dir = testing::fresh_dir("image_file");
  const cv::Mat m = picture(1);
  const std::vector<std::uint8_t> b = encode(m, {cv::IMWRITE_JPEG_QUALITY, 90});
  // Whole, and whole with a trailer (no EOI at the end: the markers are walked): as OpenCV reads
  // it.
  std::vector<std::uint8_t> trailed = b;
  trailed.insert(trailed.end(), {'x', 'y', 'z'});
  for (const auto& [name, bytes] : {std::pair{"whole.jpg", b}, std::pair{"trailed.jpg", trailed}}) {
    write(dir / name, bytes);
    const cv::Mat got = io::read_gray_image(dir / name);
    const cv::Mat want = cv::imread((dir / name).string(), cv::IMREAD_GRAYSCALE);
    ASSERT_FALSE(want.empty()) << name;
    EXPECT_EQ(cv::norm(got, want, cv::NORM_INF), 0.0) << name;
  }
  // Cut short: OpenCV alone gives an image (the rest gray); here one line naming the file.
  const fs::path cut = dir / "cut.jpg";
  write(cut, std::vector<std::uint8_t>(b.begin(), b.begin() + static_cast<long>(b.size() * 3 / 4)));
  EXPECT_FALSE(cv::imread(cut.string(), cv::IMREAD_GRAYSCALE).empty());
  test::expect_input_error([&] { io::read_gray_image(cut); }, {cut.string(), "JPEG cut short"});
  // Two bytes short: only the EOI marker missing.
  const fs::path no_eoi = dir / "no_eoi.jpg";
  write(no_eoi, std::vector<std::uint8_t>(b.begin(), b.end() - 2));
  test::expect_input_error([&] { io::read_gray_image(no_eoi); }, {no_eoi.string(), "EOI"});
  // A PNG cut short (libpng would fail, with a line of its own), and one whole with a trailer.
  std::vector<std::uint8_t> png;
  cv::imencode(".png", m, png);
  const fs::path cut_png = dir / "cut.png";
  write(cut_png, std::vector<std::uint8_t>(png.begin(), png.begin() + 40));
  test::expect_input_error([&] { io::read_gray_image(cut_png); },
                           {cut_png.string(), "PNG cut short"});
  std::vector<std::uint8_t> trailed_png = png;
  trailed_png.insert(trailed_png.end(), {'x', 'y', 'z'});
  write(dir / "trailed.png", trailed_png);
  EXPECT_EQ(cv::norm(io::read_gray_image(dir / "trailed.png"), m, cv::NORM_INF), 0.0);
  // Not an image at all: what OpenCV cannot decode, one line naming the file.
  write(dir / "text.png", {'n', 'o', 't', ' ', 'a', 'n', ' ', 'i', 'm', 'a', 'g', 'e'});
  test::expect_input_error([&] { io::read_gray_image(dir / "text.png"); }, {"text.png"});
  test::expect_input_error([&] { io::read_gray_image(dir / "none.jpg"); }, {"none.jpg"});
}

// The images netvmo reads are told by their extension in any case; list_images finds every one
// below a folder, sorted by path, and nothing else.
TEST(ImageFile, ListImagesFindsEveryImageBelowAFolderSorted) {
  for (const char* name :
       {"a.png", "a.PNG", "b.jpg", "b.JPEG", "c.pgm", "d.Bmp", "e.tif", "e.TIFF"})
    EXPECT_TRUE(io::is_image_file(name)) << name;
  for (const char* name : {"a.txt", "png", "a.png.bak", "a.gif", "calib.yaml", "a.jpg2"})
    EXPECT_FALSE(io::is_image_file(name)) << name;

  const fs::path dir = testing::fresh_dir("list_images");
  fs::create_directories(dir / "sub" / "deeper");
  fs::create_directories(dir / "folder.png");  // a folder, whatever its name
  for (const char* name :
       {"d.TIFF", "a.PNG", "sub/b.jpg", "sub/deeper/c.Bmp", "notes.txt", "sub/calib.yaml", "e.pgm"})
    write(dir / name, {1, 2, 3});
  const std::vector<fs::path> want = {dir / "a.PNG", dir / "d.TIFF", dir / "e.pgm",
                                      dir / "sub" / "b.jpg", dir / "sub" / "deeper" / "c.Bmp"};
  EXPECT_EQ(io::list_images(dir), want);
  // Not a folder: one line naming it.
  test::expect_input_error([&] { io::list_images(dir / "a.PNG"); },
                           {(dir / "a.PNG").string(), "not a folder"});
  test::expect_input_error([&] { io::list_images(dir / "none"); },
                           {(dir / "none").string(), "not a folder"});
}

// The repository's real photos, JPEG (phones and cameras: EXIF, thumbnails, their own tables) and
// PNG, are complete, and each cut at half of its length is found.
TEST(ImageFile, RealPhotosAreCompleteAndTheirCutsFound) {
  int photos[2] = {0, 0};  // JPEG, PNG
  for (const auto& e : fs::recursive_directory_iterator(fs::path(NETVMO_SOURCE_DIR) / "datasets" /
                                                        "real_photos" / "photos")) {
    std::string ext = e.path().extension().string();
    for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    if (ext != ".jpg" && ext != ".jpeg" && ext != ".png") continue;
    std::ifstream in(e.path(), std::ios::binary);
    const std::vector<std::uint8_t> b((std::istreambuf_iterator<char>(in)), {});
    ++photos[ext == ".png"];
    EXPECT_EQ(io::image_cut_short(b.data(), b.size()), "") << e.path();
    EXPECT_NE(io::image_cut_short(b.data(), b.size() / 2), "") << e.path();
  }
  EXPECT_GE(photos[0], 10);
  EXPECT_GE(photos[1], 10);
}

}  // namespace
}  // namespace netvmo
