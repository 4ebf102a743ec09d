//! The previewer's Vulkan device (issue 6, build item 1). `scripts/test.sh` installs lavapipe
//! (`mesa-vulkan-drivers`) and the validation layer; a missing device fails these tests
//! instead of skipping them (docs/design.md §11).

use wpbgi::preview::device::Gpu;

/// With the validation layer on, setting up the device and naming a resource draws no warning
/// or error from it.
#[test]
fn device_sets_up_cleanly_under_validation() {
    let gpu = Gpu::new(true).expect("a Vulkan device and the validation layer (scripts/test.sh)");
    eprintln!("device: {} ({:?})", gpu.name, gpu.kind);
    assert!(!gpu.name.is_empty());
    gpu.name(gpu.queue, "a renamed queue").expect("named");
    let messages = gpu.validation_messages();
    assert!(messages.is_empty(), "{messages:#?}");
}

/// Without validation the same device is chosen.
#[test]
fn the_choice_does_not_depend_on_validation() {
    let plain = Gpu::new(false).expect("a Vulkan device");
    let validated = Gpu::new(true).expect("a Vulkan device and the validation layer");
    assert_eq!(plain.name, validated.name);
    assert!(plain.validation_messages().is_empty());
}
