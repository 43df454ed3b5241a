#include "view/protocol.h"

#include <gtest/gtest.h>

namespace tangent::view {
namespace {

std::string ErrorOf(const std::string& text) {
  try {
    ParseClientMessage(text);
  } catch (const ProtocolError& e) {
    return e.what();
  }
  return "(accepted)";
}

TEST(ProtocolTest, ParsesEveryMessageKind) {
  EXPECT_EQ(ParseClientMessage(R"({"type":"need","hash":"0123456789abcdef"})").hash,
            "0123456789abcdef");
  const ClientMessage c =
      ParseClientMessage(R"({"type":"camera","position":[1,2,3],"target":[0,0,0.5]})");
  EXPECT_EQ(c.kind, ClientMessage::Kind::kCamera);
  EXPECT_EQ(c.camera_position, Eigen::Vector3d(1, 2, 3));
  EXPECT_EQ(c.camera_target, Eigen::Vector3d(0, 0, 0.5));
  EXPECT_EQ(ParseClientMessage(R"({"type":"play"})").kind, ClientMessage::Kind::kPlay);
  EXPECT_EQ(ParseClientMessage(R"({"type":"pause"})").kind, ClientMessage::Kind::kPause);
  EXPECT_DOUBLE_EQ(ParseClientMessage(R"({"type":"seek","t":2.5})").t, 2.5);
  // "\x89PNG\r\n\x1a\n" + "ok" in base64.
  const ClientMessage p = ParseClientMessage(
      R"({"type":"png","utime":7,"data":"data:image/png;base64,iVBORw0KGgpvaw=="})");
  EXPECT_EQ(p.utime, 7);
  EXPECT_EQ(p.png, std::string("\x89PNG\r\n\x1a\nok"));
}

TEST(ProtocolTest, BadMessagesNameWhatIsWrong) {
  EXPECT_EQ(ErrorOf("{not json"), "message is not JSON");
  EXPECT_EQ(ErrorOf("[1,2]"), "message is not a JSON object");
  EXPECT_EQ(ErrorOf(R"({"kind":"need"})"), "message has no string field \"type\"");
  EXPECT_EQ(ErrorOf(R"({"type":"launch"})"), "unknown message type \"launch\"");
  EXPECT_EQ(ErrorOf(R"({"type":"need"})"), "\"need\" message: missing field \"hash\"");
  EXPECT_EQ(ErrorOf(R"({"type":"need","hash":"abc"})"),
            "\"need\" message: \"hash\" must be a string of 16 hex digits");
  EXPECT_EQ(ErrorOf(R"({"type":"camera","position":[1,2],"target":[0,0,0]})"),
            "\"camera\" message: \"position\" must be an array of 3 numbers");
  EXPECT_EQ(ErrorOf(R"({"type":"camera","position":[1,"x",3],"target":[0,0,0]})"),
            "\"camera\" message: \"position\"[1] must be a finite number");
  EXPECT_EQ(ErrorOf(R"({"type":"camera","position":[1,1,1],"target":[1,1,1]})"),
            "\"camera\" message: position and target coincide");
  EXPECT_EQ(ErrorOf(R"({"type":"seek","t":"soon"})"),
            "\"seek\" message: \"t\" must be a finite number of seconds");
  EXPECT_EQ(ErrorOf(R"({"type":"png","utime":1.5,"data":""})"),
            "\"png\" message: \"utime\" must be an integer");
  EXPECT_EQ(ErrorOf(R"({"type":"png","utime":1,"data":"data:image/jpeg;base64,AAAA"})"),
            "\"png\" message: \"data\" must be a data:image/png;base64 URL");
  EXPECT_EQ(ErrorOf(R"({"type":"png","utime":1,"data":"data:image/png;base64,AAA"})"),
            "base64: length 3 is not a multiple of 4");
  EXPECT_EQ(ErrorOf(R"({"type":"png","utime":1,"data":"data:image/png;base64,AA*A"})"),
            "base64: invalid character at offset 2");
  EXPECT_EQ(ErrorOf(R"({"type":"png","utime":1,"data":"data:image/png;base64,AAAA"})"),
            "\"png\" message: the data is not a PNG (no PNG signature)");
}

TEST(ProtocolTest, Base64RoundTripsEveryByteAndPadding) {
  EXPECT_EQ(DecodeBase64(""), "");
  EXPECT_EQ(DecodeBase64("TQ=="), "M");
  EXPECT_EQ(DecodeBase64("TWE="), "Ma");
  EXPECT_EQ(DecodeBase64("TWFu"), "Man");
  EXPECT_EQ(DecodeBase64("AP8A/w=="), std::string("\x00\xff\x00\xff", 4));
  EXPECT_THROW(DecodeBase64("T=Fu"), ProtocolError);  // padding only at the end
  EXPECT_THROW(DecodeBase64("TW=u"), ProtocolError);
  EXPECT_THROW(DecodeBase64("===="), ProtocolError);
}

}  // namespace
}  // namespace tangent::view
