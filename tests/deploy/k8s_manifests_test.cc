// The Kubernetes manifests, parsed (yaml-cpp) and checked against each other, the container
// recipes, the binaries' flags and the docs: required fields, images, ports, probes, volumes and
// secrets consistent across files.
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <map>

#include "tests/deploy/deploy_files.h"

namespace endorecon::testing {
namespace fs = std::filesystem;
namespace {

struct Manifests {
  std::map<std::string, std::vector<YAML::Node>> by_kind;
  Manifests() {
    for (const auto& file : fs::directory_iterator(SourcePath("deploy/k8s"))) {
      if (file.path().extension() != ".yaml") continue;
      for (const auto& document : YAML::LoadAllFromFile(file.path().string())) {
        EXPECT_TRUE(document["apiVersion"] && document["kind"] && document["metadata"]["name"])
            << file.path() << ": a document without apiVersion, kind or metadata.name";
        by_kind[document["kind"].as<std::string>()].push_back(document);
      }
    }
  }
  const std::vector<YAML::Node>& Of(const std::string& kind) { return by_kind[kind]; }
};

std::vector<std::string> Command(const YAML::Node& container) {
  std::vector<std::string> command;
  for (const auto& word : container["command"]) command.push_back(word.as<std::string>());
  return command;
}

// The value after `flag` in `command`, or "".
std::string FlagValue(const std::vector<std::string>& command, const std::string& flag) {
  for (std::size_t i = 0; i + 1 < command.size(); ++i) {
    if (command[i] == flag) return command[i + 1];
  }
  return "";
}

int PortOf(const std::string& address) { return std::stoi(address.substr(address.rfind(':') + 1)); }

std::map<std::string, int> ContainerPorts(const YAML::Node& container) {
  std::map<std::string, int> ports;
  for (const auto& port : container["ports"])
    ports[port["name"].as<std::string>()] = port["containerPort"].as<int>();
  return ports;
}

TEST(K8sManifestsTest, DeploymentsAreConsistentWithImagesFlagsVolumesAndPorts) {
  Manifests manifests;
  ASSERT_EQ(manifests.Of("Deployment").size(), 2u);
  std::set<std::string> claims;
  for (const auto& claim : manifests.Of("PersistentVolumeClaim"))
    claims.insert(claim["metadata"]["name"].as<std::string>());
  const std::string docs = ReadBytes(SourcePath("docs/operations.md"));
  bool has_gpu_worker = false;
  for (const auto& deployment : manifests.Of("Deployment")) {
    const std::string name = deployment["metadata"]["name"].as<std::string>();
    const auto pod = deployment["spec"]["template"];
    EXPECT_EQ(deployment["spec"]["selector"]["matchLabels"]["app"].as<std::string>(),
              pod["metadata"]["labels"]["app"].as<std::string>())
        << name;
    std::map<std::string, YAML::Node> volumes;
    for (const auto& volume : pod["spec"]["volumes"])
      volumes[volume["name"].as<std::string>()] = static_cast<const YAML::Node&>(volume);
    ASSERT_TRUE(pod["spec"]["containers"].size() > 0) << name;
    for (const auto& container : pod["spec"]["containers"]) {
      // The image is built by a recipe of the same name, which copies the binary the pod starts.
      const std::string image = container["image"].as<std::string>();
      const std::string image_name = image.substr(0, image.find(':'));
      EXPECT_NE(image.find(':'), std::string::npos) << image << ": pin a tag";
      const auto recipe = SourcePath("deploy/containers/" + image_name + ".Dockerfile");
      ASSERT_TRUE(fs::exists(recipe)) << name << ": no recipe " << recipe;
      const auto command = Command(container);
      ASSERT_FALSE(command.empty()) << name;
      EXPECT_NE(ReadBytes(recipe).find("/usr/local/bin/" + command[0] + "\n"), std::string::npos)
          << recipe << " does not copy " << command[0];

      // Every flag is one the binary accepts.
      const bool subcommand = command.size() > 1 && command[1].rfind("--", 0) != 0;
      const auto accepted = AcceptedFlags(BinaryNamed(command[0]), subcommand ? command[1] : "");
      ASSERT_FALSE(accepted.empty()) << command[0] << " --help printed no flags";
      for (const auto& word : command) {
        if (word.rfind("--", 0) == 0) {
          EXPECT_TRUE(accepted.count(word)) << name << ": " << command[0] << " has no " << word;
        }
      }

      // Every mount has its volume, every secret is one the docs say how to create, every claim
      // exists, and every file the command names lies in a mount.
      std::vector<std::string> mounts;
      for (const auto& mount : container["volumeMounts"]) {
        const std::string volume = mount["name"].as<std::string>();
        ASSERT_TRUE(volumes.count(volume)) << name << ": mount of unknown volume " << volume;
        mounts.push_back(mount["mountPath"].as<std::string>());
        if (volumes[volume]["secret"]) {
          const std::string secret = volumes[volume]["secret"]["secretName"].as<std::string>();
          EXPECT_NE(docs.find("kubectl create secret generic " + secret), std::string::npos)
              << secret << ": docs/operations.md does not say how to create it";
          const auto mode =
              volumes[volume]["secret"]["defaultMode"].as<std::string>();  // octal, as YAML 1.1 reads it
          EXPECT_EQ(std::stoi(mode, nullptr, 8) & 07, 0) << secret << " readable by others";
        }
        if (volumes[volume]["persistentVolumeClaim"]) {
          EXPECT_TRUE(claims.count(volumes[volume]["persistentVolumeClaim"]["claimName"].as<std::string>()))
              << name;
        }
      }
      for (const auto& flag : {"--tls-cert", "--tls-key", "--tls-client-ca", "--ca", "--token-file",
                               "--data-dir", "--work-dir"}) {
        const auto path = FlagValue(command, flag);
        if (path.empty()) continue;
        EXPECT_TRUE(std::any_of(mounts.begin(), mounts.end(),
                                [&](const std::string& mount) { return path.rfind(mount, 0) == 0; }))
            << name << ": " << flag << " " << path << " is not in a mounted volume";
      }
      // A volume's root is group-owned under fsGroup: the data and scratch folders are folders below
      // it, which the binaries create their owner's alone (each start warned of the root).
      for (const auto& flag : {"--data-dir", "--work-dir"}) {
        const auto path = FlagValue(command, flag);
        EXPECT_EQ(std::count(mounts.begin(), mounts.end(), path), 0)
            << name << ": " << flag << " is a volume's root";
      }
      EXPECT_FALSE(FlagValue(command, "--tls-key").empty() && FlagValue(command, "--ca").empty())
          << name << " talks without TLS";

      // Ports: gRPC, probes on the health port, metrics where Prometheus is told to look.
      const auto ports = ContainerPorts(container);
      const auto metrics_port = FlagValue(command, "--metrics-port");
      ASSERT_FALSE(metrics_port.empty()) << name;
      EXPECT_EQ(ports.at("metrics"), std::stoi(metrics_port)) << name;
      EXPECT_EQ(pod["metadata"]["annotations"]["prometheus.io/port"].as<std::string>(), metrics_port) << name;
      EXPECT_EQ(FlagValue(command, "--metrics-host"), "0.0.0.0") << name << ": Prometheus could not reach it";
      if (command[0] == "endorecon-server") {
        EXPECT_EQ(ports.at("grpc"), PortOf(FlagValue(command, "--listen")));
        const int health = PortOf(FlagValue(command, "--health-listen"));
        EXPECT_EQ(ports.at("health"), health);
        for (const auto* probe : {"readinessProbe", "livenessProbe"})
          EXPECT_EQ(container[probe]["grpc"]["port"].as<int>(), health) << probe;
      }
      if (container["resources"]["limits"]["nvidia.com/gpu"]) {
        has_gpu_worker = true;
        EXPECT_EQ(container["resources"]["limits"]["nvidia.com/gpu"].as<int>(), 1);
        EXPECT_EQ(FlagValue(command, "--devices"), "0") << "one GPU per pod, seen as device 0";
      }
      EXPECT_TRUE(container["resources"]["requests"]) << name << " has no resource requests";
    }
  }
  EXPECT_TRUE(has_gpu_worker);
}

TEST(K8sManifestsTest, ServicesReachTheirPodsAndWorkersTheServer) {
  Manifests manifests;
  std::map<std::string, YAML::Node> deployments;
  for (const auto& deployment : manifests.Of("Deployment"))
    deployments[deployment["spec"]["template"]["metadata"]["labels"]["app"].as<std::string>()] = deployment;
  std::map<std::string, int> service_ports;
  for (const auto& service : manifests.Of("Service")) {
    const std::string app = service["spec"]["selector"]["app"].as<std::string>();
    ASSERT_TRUE(deployments.count(app)) << "service selects no deployment: " << app;
    const auto ports = ContainerPorts(deployments[app]["spec"]["template"]["spec"]["containers"][0]);
    for (const auto& port : service["spec"]["ports"]) {
      EXPECT_TRUE(ports.count(port["targetPort"].as<std::string>())) << port["targetPort"].as<std::string>();
      if (port["name"].as<std::string>() == "grpc")
        service_ports[service["metadata"]["name"].as<std::string>()] = port["port"].as<int>();
    }
  }
  for (const auto& [app, deployment] : deployments) {
    const auto command = Command(deployment["spec"]["template"]["spec"]["containers"][0]);
    const auto server = FlagValue(command, "--server");
    if (server.empty()) continue;
    const std::string host = server.substr(0, server.rfind(':'));
    ASSERT_TRUE(service_ports.count(host)) << app << " talks to " << server << ", which no service offers";
    EXPECT_EQ(service_ports[host], PortOf(server));
  }
  // Each NetworkPolicy selects a deployment's pods and opens ports those pods name.
  EXPECT_EQ(manifests.Of("NetworkPolicy").size(), 2u);
  for (const auto& policy : manifests.Of("NetworkPolicy")) {
    const std::string app = policy["spec"]["podSelector"]["matchLabels"]["app"].as<std::string>();
    ASSERT_TRUE(deployments.count(app)) << "network policy selects no deployment: " << app;
    const auto ports = ContainerPorts(deployments[app]["spec"]["template"]["spec"]["containers"][0]);
    for (const auto& rule : policy["spec"]["ingress"]) {
      for (const auto& port : rule["ports"]) EXPECT_TRUE(ports.count(port["port"].as<std::string>())) << app;
    }
  }
}

}  // namespace
}  // namespace endorecon::testing
